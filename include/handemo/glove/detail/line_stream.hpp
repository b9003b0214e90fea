// Line framing over a POSIX file descriptor, shared by the serial and TCP transports: bytes are read with
// poll() and a timeout, split at '\n' (a '\r' before it is dropped), and a line longer than the limit is
// cut there: its first `max_line` bytes are returned (a decoder then refuses them, so the fault is counted)
// and the rest up to the next line end is skipped. A partial line waits for its end across reads; at a
// disconnect it is dropped and counted, never handed out as if complete.
#pragma once

#include <handemo/core/error.hpp>

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace handemo::detail {

/// @brief Splits a byte stream into lines.
class line_splitter {
public:
    explicit line_splitter(std::size_t max_line = 4096) : max_(max_line) {}
    /// Appends received bytes.
    void feed(std::span<const std::uint8_t> b) { buf_.insert(buf_.end(), b.begin(), b.end()); }
    /// The next complete line (without "\n" or "\r\n"), or empty when none is buffered.
    std::optional<std::vector<std::uint8_t>> next()
    {
        for (;;) {
            std::size_t end = 0;
            while (end < buf_.size() && buf_[end] != '\n') ++end;
            if (end == buf_.size()) {
                if (buf_.size() <= max_) return std::nullopt;
                // an overlong line: hand out its head, skip the rest up to its end
                std::vector<std::uint8_t> head(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(max_));
                buf_.clear();
                skipping_ = true;
                ++overlong_;
                return head;
            }
            std::vector<std::uint8_t> line(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(end));
            buf_.erase(buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(end) + 1);
            if (skipping_) {
                skipping_ = false;
                continue;
            }
            if (!line.empty() && line.back() == '\r') line.pop_back();
            if (line.size() > max_) {
                line.resize(max_);
                ++overlong_;
            }
            return line;
        }
    }
    /// Drops a partial line (after a disconnect); counts it when there was one.
    void reset()
    {
        if (!buf_.empty() && !skipping_) ++partial_dropped_;
        buf_.clear();
        skipping_ = false;
    }
    /// Bytes of a line whose end has not come yet (0 while skipping the rest of a cut line).
    std::size_t pending() const noexcept { return skipping_ ? 0 : buf_.size(); }
    std::size_t overlong() const noexcept { return overlong_; }
    std::size_t partial_dropped() const noexcept { return partial_dropped_; }

private:
    std::size_t max_;
    std::vector<std::uint8_t> buf_;
    bool skipping_ = false;
    std::size_t overlong_ = 0, partial_dropped_ = 0;
};

/// What one wait-and-read on a descriptor gave.
enum class fd_read : std::uint8_t { data, timeout, closed };

/// @brief Waits up to `timeout` for `fd` to be readable and reads what is there into `out`.
/// @throws device_error naming `name` on a read error other than a closed peer.
inline fd_read read_some(int fd, std::chrono::milliseconds timeout, std::vector<std::uint8_t>& out, const std::string& name)
{
    pollfd p{fd, POLLIN, 0};
    int r;
    do r = ::poll(&p, 1, static_cast<int>(timeout.count()));
    while (r < 0 && errno == EINTR);
    if (r < 0) throw device_error("glove: " + name + ": poll failed: " + std::strerror(errno));
    if (r == 0) return fd_read::timeout;
    std::uint8_t buf[1024];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n > 0) {
        out.assign(buf, buf + n);
        return fd_read::data;
    }
    if (n == 0 || (p.revents & (POLLHUP | POLLERR)) || errno == ECONNRESET || errno == EIO) return fd_read::closed;
    if (errno == EAGAIN || errno == EINTR) return fd_read::timeout;
    throw device_error("glove: " + name + ": read failed: " + std::strerror(errno));
}

/// @brief Writes all of `b` to `fd`. @throws device_error naming `name`.
inline void write_all(int fd, std::span<const std::uint8_t> b, const std::string& name)
{
    std::size_t done = 0;
    while (done < b.size()) {
        const ssize_t n = ::write(fd, b.data() + done, b.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0 && errno == EAGAIN) {
            pollfd p{fd, POLLOUT, 0};
            ::poll(&p, 1, 100);
            continue;
        }
        if (n <= 0) throw device_error("glove: " + name + ": write failed: " + std::strerror(errno));
        done += static_cast<std::size_t>(n);
    }
}

}  // namespace handemo::detail
