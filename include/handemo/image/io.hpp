// Image files for the motion images of Eq. 3 / Eq. 6 (Chan, Irimia, Ho 2020): lossless 24-bit BMP and
// 8-bit RGB PNG, written into memory with stb_image_write and then atomically to disk, read back with
// stb_image after checking the header (format, size, channel count, bit depth) with stbi_info, so a
// grayscale, RGBA, 16-bit, truncated or absurdly large file is refused with a clear error instead of
// being silently converted. The stb implementation comes from Debian's libstb (target handemo::image);
// this header never defines STB_IMAGE_IMPLEMENTATION.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/image/rgb_image.hpp>

#include <stb_image.h>
#include <stb_image_write.h>

#include <algorithm>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

namespace handemo {

/// Largest width or height handemo reads or writes (larger headers are treated as corrupt).
inline constexpr std::size_t image_max_side = std::size_t{1} << 15;
/// Largest pixel count handemo reads or writes (64 Mi pixels, 192 MiB of RGB).
inline constexpr std::size_t image_max_pixels = std::size_t{1} << 26;

namespace detail {

inline void check_image_size(const std::string& what, std::size_t w, std::size_t h)
{
    if (w == 0 || h == 0 || w > image_max_side || h > image_max_side || w * h > image_max_pixels)
        throw shape_error(what + ": size " + std::to_string(w) + "x" + std::to_string(h) +
                          " is empty or too large (at most " + std::to_string(image_max_side) + " per side and " +
                          std::to_string(image_max_pixels) + " pixels)");
}

inline void append_to_string(void* ctx, void* data, int size)
{
    static_cast<std::string*>(ctx)->append(static_cast<const char*>(data), static_cast<std::size_t>(size));
}

inline std::uint32_t read_le32(std::string_view d, std::size_t at) noexcept
{
    return static_cast<std::uint32_t>(static_cast<unsigned char>(d[at])) |
           static_cast<std::uint32_t>(static_cast<unsigned char>(d[at + 1])) << 8 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(d[at + 2])) << 16 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(d[at + 3])) << 24;
}

inline std::string stb_reason()
{
    const char* r = stbi_failure_reason();
    return r ? r : "unknown stb_image error";
}

}  // namespace detail

/// @brief Writes a 24-bit uncompressed BMP (lossless), atomically.
/// @throws shape_error for an empty, inconsistent or oversized image; io_error when writing fails.
inline void write_bmp(const std::filesystem::path& path, const rgb_image& im)
{
    const std::string what = "write_bmp: " + path.string();
    im.validate(what);
    detail::check_image_size(what, im.width, im.height);
    std::string out;
    out.reserve(54 + (im.width * 3 + 3) / 4 * 4 * im.height);
    if (!stbi_write_bmp_to_func(detail::append_to_string, &out, static_cast<int>(im.width),
                                static_cast<int>(im.height), 3, im.pixels.data()))
        throw io_error(what + ": stbi_write_bmp_to_func failed");
    write_file_atomic(path, out);
}

/// @brief Writes an 8-bit RGB PNG (lossless), atomically.
/// @throws shape_error for an empty, inconsistent or oversized image; io_error when writing fails.
inline void write_png(const std::filesystem::path& path, const rgb_image& im)
{
    const std::string what = "write_png: " + path.string();
    im.validate(what);
    detail::check_image_size(what, im.width, im.height);
    std::string out;
    if (!stbi_write_png_to_func(detail::append_to_string, &out, static_cast<int>(im.width),
                                static_cast<int>(im.height), 3, im.pixels.data(), static_cast<int>(im.width * 3)))
        throw io_error(what + ": stbi_write_png_to_func failed");
    write_file_atomic(path, out);
}

/// @brief Decodes an in-memory BMP or PNG that must be 8-bit, 3-channel RGB.
/// @param source_name the file name used in error messages.
/// @throws format_error for another format, a corrupt or truncated file (with stb's reason), a channel
/// count other than 3 (grayscale, gray+alpha, RGBA), 16 bits per channel; shape_error for absurd sizes.
inline rgb_image decode_image(std::string_view data, std::string_view source_name)
{
    const std::string what = "read_image: " + std::string(source_name);
    const bool is_png = data.size() >= 8 && data.substr(0, 8) == std::string_view("\x89PNG\r\n\x1a\n", 8);
    const bool is_bmp = data.size() >= 2 && data.substr(0, 2) == "BM";
    if (!is_png && !is_bmp)
        throw format_error(what + ": not a BMP or PNG file (" + std::to_string(data.size()) +
                           " bytes, no BM or \\x89PNG signature)");
    if (data.size() > static_cast<std::size_t>(INT_MAX))
        throw format_error(what + ": file of " + std::to_string(data.size()) + " bytes is too large");
    const auto* buf = reinterpret_cast<const stbi_uc*>(data.data());
    const int len = static_cast<int>(data.size());
    int w = 0, h = 0, comp = 0;
    if (!stbi_info_from_memory(buf, len, &w, &h, &comp))
        throw format_error(what + ": corrupt " + (is_png ? "PNG" : "BMP") + " header: " + detail::stb_reason());
    if (w <= 0 || h <= 0) throw format_error(what + ": size " + std::to_string(w) + "x" + std::to_string(h) + " is empty");
    detail::check_image_size(what, static_cast<std::size_t>(w), static_cast<std::size_t>(h));
    const bool deep = stbi_is_16_bit_from_memory(buf, len) != 0;
    if (comp != 3 || deep)
        throw format_error(what + ": " + std::to_string(comp) + " channel" + (comp == 1 ? "" : "s") +
                           (deep ? " of 16 bits" : "") + " found, expected 3 (8-bit RGB)");
    if (is_bmp && data.size() >= 34) {
        // stb_image fills missing BMP pixel data with zeros; refuse truncated files explicitly.
        const std::uint32_t declared = detail::read_le32(data, 2), offset = detail::read_le32(data, 10);
        const unsigned bpp = static_cast<unsigned char>(data[28]) | static_cast<unsigned>(static_cast<unsigned char>(data[29])) << 8;
        const std::uint32_t compression = detail::read_le32(data, 30);
        std::size_t need = declared;
        if (compression == 0 && (bpp == 24 || bpp == 32)) {
            const std::size_t stride = (static_cast<std::size_t>(w) * (bpp / 8) + 3) / 4 * 4;
            need = std::max(need, static_cast<std::size_t>(offset) + stride * static_cast<std::size_t>(h));
        }
        if (data.size() < need)
            throw format_error(what + ": truncated BMP: " + std::to_string(data.size()) + " bytes, header needs " +
                               std::to_string(need));
    }
    int n = 0;
    std::unique_ptr<stbi_uc, void (*)(void*)> px(stbi_load_from_memory(buf, len, &w, &h, &n, 3), stbi_image_free);
    if (!px) throw format_error(what + ": corrupt or truncated " + (is_png ? "PNG" : "BMP") + ": " + detail::stb_reason());
    rgb_image im;
    im.width = static_cast<std::size_t>(w);
    im.height = static_cast<std::size_t>(h);
    im.pixels.assign(px.get(), px.get() + im.width * im.height * 3);
    return im;
}

/// @brief Reads a BMP or PNG file that must be 8-bit, 3-channel RGB.
/// @throws io_error when the file cannot be read; format_error / shape_error as decode_image.
inline rgb_image read_image(const std::filesystem::path& path) { return decode_image(read_file(path), path.string()); }

/// @brief Reads a BMP or PNG file and checks its size.
/// @throws shape_error naming the file, the size found and the size expected, plus read_image's errors.
inline rgb_image read_image(const std::filesystem::path& path, std::size_t expected_width, std::size_t expected_height)
{
    rgb_image im = read_image(path);
    if (im.width != expected_width || im.height != expected_height)
        throw shape_error("read_image: " + path.string() + ": size " + std::to_string(im.width) + "x" +
                          std::to_string(im.height) + " (width x height), expected " + std::to_string(expected_width) +
                          "x" + std::to_string(expected_height));
    return im;
}

}  // namespace handemo
