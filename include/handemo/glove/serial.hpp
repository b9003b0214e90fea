// Text-line transports over POSIX descriptors: a serial port (termios: the baud rate, 8 data bits, no
// parity, one stop bit, raw mode; USB serial and Bluetooth RFCOMM gloves such as OpenGloves/LucidGloves)
// and the shared base that frames lines (detail/line_stream.hpp), counts cut and partial lines, reopens
// after a disconnect and names the device in every error. tcp.hpp adds the TCP line stream.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/glove/detail/line_stream.hpp>
#include <handemo/glove/transport.hpp>

#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

namespace handemo {

/// @brief A line-framed stream on a file descriptor; subclasses open and name it.
class line_transport : public glove_transport {
public:
    line_transport(const line_transport&) = delete;
    line_transport& operator=(const line_transport&) = delete;
    ~line_transport() override { close(); }

    /// @return the next complete line (a report), or empty after `timeout` without one.
    /// @throws device_error naming the device when it closes or fails (a partial line is dropped).
    std::optional<hid_report> read(std::chrono::milliseconds timeout) override
    {
        if (fd_ < 0) throw device_error("glove: " + name() + " is not open");
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        for (;;) {
            if (auto line = lines_.next()) return hid_report{std::move(*line), host_seconds(), 0};
            const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
            if (left.count() < 0) return std::nullopt;
            switch (detail::read_some(fd_, left, chunk_, name())) {
            case detail::fd_read::data: lines_.feed(chunk_); break;
            case detail::fd_read::timeout:
                if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
                break;
            case detail::fd_read::closed: {
                const std::size_t partial = lines_.pending();
                close();
                throw device_error("glove: " + name() + " disconnected (" + closed_what() + ")" +
                                   (partial ? "; a partial line of " + std::to_string(partial) + " bytes was dropped" : ""));
            }
            }
        }
    }

    bool reconnect() override
    {
        close();
        try {
            fd_ = open_fd();
            return true;
        } catch (const device_error&) {
            return false;
        }
    }

    /// Sends a command line (the caller ends it with '\n').
    void write(std::span<const std::uint8_t> b) override
    {
        if (fd_ < 0) throw device_error("glove: " + name() + " is not open");
        detail::write_all(fd_, b, name());
    }
    /// Lines cut at the length limit.
    std::size_t overlong_lines() const noexcept { return lines_.overlong(); }
    /// Partial lines dropped at a disconnect.
    std::size_t partial_lines() const noexcept { return lines_.partial_dropped(); }

protected:
    explicit line_transport(std::size_t max_line) : lines_(max_line) {}
    /// Opens the descriptor. @throws device_error naming the device.
    virtual int open_fd() = 0;
    /// What a closed stream means for this device ("the cable was pulled", "the server closed").
    virtual std::string closed_what() const = 0;
    /// Called from the subclass constructor.
    void open_now() { fd_ = open_fd(); }
    void close() noexcept
    {
        if (fd_ >= 0) ::close(fd_), fd_ = -1;
        lines_.reset();
    }

private:
    int fd_ = -1;
    detail::line_splitter lines_;
    std::vector<std::uint8_t> chunk_;
};

namespace detail {

inline speed_t baud_constant(int baud)
{
    switch (baud) {
    case 9600: return B9600;
    case 19200: return B19200;
    case 38400: return B38400;
    case 57600: return B57600;
    case 115200: return B115200;
    case 230400: return B230400;
    case 460800: return B460800;
    case 921600: return B921600;
    default:
        throw value_error("glove serial: baud rate " + std::to_string(baud) +
                          " is not one of 9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600");
    }
}

}  // namespace detail

/// @brief A serial port read as text lines: raw mode, 8N1, no flow control.
class serial_transport : public line_transport {
public:
    /// @param path e.g. /dev/ttyUSB0, /dev/ttyACM0, /dev/rfcomm0 (a pseudo-terminal in tests).
    /// @param baud 115200 for OpenGloves firmware over USB.
    /// @throws device_error naming the port when it cannot be opened or configured; value_error for a baud rate termios lacks.
    explicit serial_transport(std::string path, int baud = 115200, std::size_t max_line = 4096)
        : line_transport(max_line), path_(std::move(path)), speed_(detail::baud_constant(baud)), baud_(baud)
    {
        open_now();
    }
    std::string name() const override { return "serial port " + path_; }
    int baud() const noexcept { return baud_; }

protected:
    int open_fd() override
    {
        const int fd = ::open(path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
        if (fd < 0)
            throw device_error("glove: cannot open " + name() + ": " + std::strerror(errno) +
                               (errno == EACCES ? " (is your user in the dialout group?)" : ""));
        termios t{};
        if (::tcgetattr(fd, &t) != 0) {
            const std::string why = std::strerror(errno);
            ::close(fd);
            throw device_error("glove: " + name() + " is not a serial port: " + why);
        }
        ::cfmakeraw(&t);
        t.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CSIZE | CRTSCTS);
        t.c_cflag |= CS8 | CREAD | CLOCAL;
        t.c_cc[VMIN] = 0;
        t.c_cc[VTIME] = 0;
        ::cfsetispeed(&t, speed_);
        ::cfsetospeed(&t, speed_);
        if (::tcsetattr(fd, TCSANOW, &t) != 0) {
            const std::string why = std::strerror(errno);
            ::close(fd);
            throw device_error("glove: cannot set " + name() + " to " + std::to_string(baud_) + " baud 8N1: " + why);
        }
        return fd;
    }
    std::string closed_what() const override { return "the cable was pulled or the device reset"; }

private:
    std::string path_;
    speed_t speed_;
    int baud_;
};

}  // namespace handemo
