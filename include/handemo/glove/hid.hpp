// The HID transport (hidapi): enumerate devices, open one by VID:PID or path, read input reports with a
// timeout, send and get feature reports, reopen after a disconnect. This is the only file of handemo that
// includes hidapi; include it after <handemo/glove.hpp> and link the CMake target handemo::glove.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/glove/transport.hpp>

#include <hidapi/hidapi.h>

#include <cstdint>
#include <cstdio>
#include <cwchar>
#include <optional>
#include <string>
#include <vector>

namespace handemo {

/// @brief One HID device as enumerated.
struct hid_device_entry {
    std::string path, manufacturer, product, serial;
    std::uint16_t vendor_id = 0, product_id = 0, usage_page = 0, usage = 0;
    int interface_number = -1;
};

namespace detail {

inline std::string narrow(const wchar_t* w)
{
    std::string s;
    if (!w) return s;
    for (; *w; ++w) s += (*w >= 0x20 && *w < 0x7f) ? static_cast<char>(*w) : '?';
    return s;
}

inline void hid_init_once()
{
    static const int rc = hid_init();
    if (rc != 0) throw device_error("glove: hid_init failed: " + narrow(hid_error(nullptr)));
}

/// Parses "VVVV:PPPP" (hex); empty when `spec` is not of that form (then it is a path).
inline std::optional<std::pair<std::uint16_t, std::uint16_t>> parse_vid_pid(const std::string& spec)
{
    const auto c = spec.find(':');
    if (c == std::string::npos || c == 0 || c + 1 >= spec.size() || spec.find('/') != std::string::npos) return std::nullopt;
    try {
        std::size_t a = 0, b = 0;
        const auto v = std::stoul(spec.substr(0, c), &a, 16), p = std::stoul(spec.substr(c + 1), &b, 16);
        if (a != c || b != spec.size() - c - 1 || v > 0xffff || p > 0xffff) return std::nullopt;
        return std::pair{static_cast<std::uint16_t>(v), static_cast<std::uint16_t>(p)};
    } catch (...) {
        return std::nullopt;
    }
}

}  // namespace detail

/// @brief Lists HID devices, optionally only those with a vendor / product id (0: any).
/// @throws device_error when hidapi cannot initialise.
inline std::vector<hid_device_entry> enumerate_hid(std::uint16_t vendor_id = 0, std::uint16_t product_id = 0)
{
    detail::hid_init_once();
    std::vector<hid_device_entry> out;
    hid_device_info* list = hid_enumerate(vendor_id, product_id);
    for (auto* d = list; d; d = d->next) {
        hid_device_entry e;
        e.path = d->path ? d->path : "";
        e.manufacturer = detail::narrow(d->manufacturer_string);
        e.product = detail::narrow(d->product_string);
        e.serial = detail::narrow(d->serial_number);
        e.vendor_id = d->vendor_id, e.product_id = d->product_id, e.usage_page = d->usage_page, e.usage = d->usage;
        e.interface_number = d->interface_number;
        out.push_back(std::move(e));
    }
    hid_free_enumeration(list);
    return out;
}

/// @brief A HID device read through hidapi.
class hid_transport : public glove_transport {
public:
    /// @param spec "VVVV:PPPP" (hex vendor:product, the first such device) or a device path (/dev/hidraw3).
    /// @param init_features feature reports sent after every open (a profile's `init_features`).
    /// @param max_report the largest input report, report id included.
    /// @throws device_error naming the device when it is not found or cannot be opened.
    explicit hid_transport(std::string spec, std::vector<std::vector<std::uint8_t>> init_features = {}, std::size_t max_report = 1024)
        : spec_(std::move(spec)), init_(std::move(init_features)), buf_(max_report)
    {
        detail::hid_init_once();
        open();
    }
    hid_transport(const hid_transport&) = delete;
    hid_transport& operator=(const hid_transport&) = delete;
    ~hid_transport() override { close(); }

    std::string name() const override { return path_.empty() || path_ == spec_ ? spec_ : spec_ + " (" + path_ + ")"; }

    std::optional<hid_report> read(std::chrono::milliseconds timeout) override
    {
        if (!dev_) throw device_error("glove: device " + name() + " is not open");
        const int n = hid_read_timeout(dev_, buf_.data(), buf_.size(), static_cast<int>(timeout.count()));
        if (n < 0) {
            const std::string why = detail::narrow(hid_error(dev_));
            close();
            throw device_error("glove: device " + name() + " disconnected or failed" + (why.empty() ? "" : ": " + why));
        }
        if (n == 0) return std::nullopt;
        return hid_report{{buf_.begin(), buf_.begin() + n}, host_seconds()};
    }

    bool reconnect() override
    {
        close();
        try {
            open();
            return true;
        } catch (const device_error&) {
            return false;
        }
    }

    void send_feature(std::span<const std::uint8_t> b) override
    {
        if (!dev_ || hid_send_feature_report(dev_, b.data(), b.size()) < 0)
            throw device_error("glove: device " + name() + ": sending feature report " + (b.empty() ? "?" : std::to_string(b[0])) +
                               " failed: " + (dev_ ? detail::narrow(hid_error(dev_)) : "not open"));
    }

    std::vector<std::uint8_t> get_feature(std::uint8_t id, std::size_t size) override
    {
        std::vector<std::uint8_t> b(std::max<std::size_t>(size, 1));
        b[0] = id;
        const int n = dev_ ? hid_get_feature_report(dev_, b.data(), b.size()) : -1;
        if (n < 0) throw device_error("glove: device " + name() + ": reading feature report " + std::to_string(id) + " failed");
        b.resize(static_cast<std::size_t>(n));
        return b;
    }

private:
    void open()
    {
        if (const auto ids = detail::parse_vid_pid(spec_)) {
            const auto list = enumerate_hid(ids->first, ids->second);
            if (list.empty()) throw device_error("glove: no HID device " + spec_ + " (see 'handemo glove list')");
            path_ = list.front().path;
        } else {
            path_ = spec_;
        }
        dev_ = hid_open_path(path_.c_str());
        if (!dev_) throw device_error("glove: cannot open HID device " + name() + ": " + detail::narrow(hid_error(nullptr)) +
                                      " (permissions of /dev/hidraw*? see 'handemo glove list')");
        for (const auto& f : init_) send_feature(f);
    }
    void close()
    {
        if (dev_) hid_close(dev_), dev_ = nullptr;
    }
    std::string spec_, path_;
    std::vector<std::vector<std::uint8_t>> init_;
    std::vector<std::uint8_t> buf_;
    hid_device* dev_ = nullptr;
};

}  // namespace handemo
