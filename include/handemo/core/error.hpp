// handemo error types: one base `handemo::error`, a few subclasses by kind of fault.
// Messages follow the house style: `<function or format>: <where (file, line, field)>: <found> <expected>`.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace handemo {

/// @brief Base of every exception handemo throws.
struct error : std::runtime_error {
    using std::runtime_error::runtime_error;
};
/// @brief Malformed data in a file or buffer (BVH, CSV, image, JSON, checkpoint).
struct format_error : error {
    using error::error;
};
/// @brief A tensor, clip or image whose shape differs from the one required.
struct shape_error : error {
    using error::error;
};
/// @brief A file that cannot be opened, read, written or renamed.
struct io_error : error {
    using error::error;
};
/// @brief A device (glove) that is missing, disconnects or sends garbage.
struct device_error : error {
    using error::error;
};
/// @brief A value outside its domain (unknown emotion, bad option, NaN where a number is required).
struct value_error : error {
    using error::error;
};

namespace detail {

/// Builds "what: file:line: msg" style messages without iostreams.
inline std::string where(std::string_view file, long line = -1)
{
    std::string s(file);
    if (line >= 0) {
        s += ":";
        s += std::to_string(line);
    }
    return s;
}

}  // namespace detail
}  // namespace handemo
