// A TCP line stream (the Senso glove's local server; an OpenGloves device behind a serial-to-TCP bridge):
// connect with a timeout, read text lines with a timeout, reconnect after the server closes, and name the
// address in every error.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/glove/serial.hpp>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace handemo {

/// @brief Splits "HOST:PORT". @throws value_error naming `spec` when it is not of that form.
inline std::pair<std::string, int> parse_host_port(const std::string& spec)
{
    const auto c = spec.rfind(':');
    int port = -1;
    if (c != std::string::npos && c > 0 && c + 1 < spec.size()) {
        try {
            std::size_t used = 0;
            port = std::stoi(spec.substr(c + 1), &used);
            if (used != spec.size() - c - 1) port = -1;
        } catch (...) {
            port = -1;
        }
    }
    if (port <= 0 || port > 65535) throw value_error("glove: '" + spec + "' is not HOST:PORT (e.g. 127.0.0.1:53450)");
    return {spec.substr(0, c), port};
}

/// @brief A TCP connection read as text lines.
class tcp_transport : public line_transport {
public:
    /// @param address "HOST:PORT".
    /// @param connect_timeout how long a connect may take.
    /// @throws device_error naming the address when nothing accepts the connection; value_error for a bad address.
    explicit tcp_transport(std::string address, std::chrono::milliseconds connect_timeout = std::chrono::milliseconds(2000),
                           std::size_t max_line = 1 << 16)
        : line_transport(max_line), address_(std::move(address)), timeout_(connect_timeout)
    {
        std::tie(host_, port_) = parse_host_port(address_);
        open_now();
    }
    std::string name() const override { return "TCP " + address_; }

protected:
    int open_fd() override
    {
        addrinfo hints{}, *res = nullptr;
        hints.ai_family = AF_UNSPEC;
        hints.ai_socktype = SOCK_STREAM;
        if (const int e = ::getaddrinfo(host_.c_str(), std::to_string(port_).c_str(), &hints, &res); e != 0)
            throw device_error("glove: " + name() + ": cannot resolve '" + host_ + "': " + ::gai_strerror(e));
        std::string why = "no address";
        for (auto* a = res; a; a = a->ai_next) {
            const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
            if (fd < 0) continue;
            int rc = ::connect(fd, a->ai_addr, a->ai_addrlen);
            if (rc != 0 && errno == EINPROGRESS) {
                pollfd p{fd, POLLOUT, 0};
                rc = ::poll(&p, 1, static_cast<int>(timeout_.count()));
                int err = 0;
                socklen_t len = sizeof err;
                if (rc == 1 && ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len) == 0 && err == 0) rc = 0;
                else errno = rc == 0 ? ETIMEDOUT : (err ? err : errno), rc = -1;
            }
            if (rc == 0) {
                const int one = 1;
                ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
                ::freeaddrinfo(res);
                return fd;
            }
            why = std::strerror(errno);
            ::close(fd);
        }
        ::freeaddrinfo(res);
        throw device_error("glove: cannot connect to " + name() + ": " + why + " (is the glove's server running?)");
    }
    std::string closed_what() const override { return "the server closed the connection"; }

private:
    std::string address_, host_;
    int port_ = 0;
    std::chrono::milliseconds timeout_;
};

}  // namespace handemo
