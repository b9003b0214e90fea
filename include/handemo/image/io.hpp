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
/// Largest pixel count handemo reads or writes (16 Mi pixels, 48 MiB of RGB), so that decoding the largest
/// image accepted (the file, stb's inflated rows and the pixels) stays under 256 MB.
inline constexpr std::size_t image_max_pixels = std::size_t{1} << 24;

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

inline std::uint32_t read_be32(std::string_view d, std::size_t at) noexcept
{
    return static_cast<std::uint32_t>(static_cast<unsigned char>(d[at])) << 24 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(d[at + 1])) << 16 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(d[at + 2])) << 8 |
           static_cast<std::uint32_t>(static_cast<unsigned char>(d[at + 3]));
}

/// CRC-32 (ISO 3309, as PNG chunks use it) of `d`.
inline std::uint32_t crc32(std::string_view d, std::uint32_t crc = 0) noexcept
{
    crc = ~crc;
    for (char ch : d) {
        crc ^= static_cast<unsigned char>(ch);
        for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
    }
    return ~crc;
}

/// Adler-32 (RFC 1950, the zlib stream's trailer) of `n` bytes.
inline std::uint32_t adler32(const unsigned char* p, std::size_t n) noexcept
{
    std::uint32_t a = 1, b = 0;
    while (n > 0) {
        const std::size_t m = n < 5552 ? n : 5552;  // largest run without overflow of b
        for (std::size_t i = 0; i < m; ++i) {
            a += p[i];
            b += a;
        }
        a %= 65521u;
        b %= 65521u;
        p += m;
        n -= m;
    }
    return b << 16 | a;
}

/// Checks a PNG before stb_image sees it (stb checks neither the chunk CRCs nor the zlib Adler-32, and
/// inflates whatever the stream holds): the chunk layout and every CRC, an 8-bit RGB IHDR within the size
/// limits, and that the IDAT stream inflates to exactly the size the header declares (into a buffer of
/// that size, so a zlib bomb stops there) with a matching Adler-32.
inline void check_png(std::string_view data, const std::string& what)
{
    auto fail = [&](const std::string& msg) { throw format_error(what + ": corrupt or truncated PNG: " + msg); };
    std::size_t at = 8;
    std::uint32_t w = 0, h = 0;
    unsigned interlace = 0;
    bool have_ihdr = false, have_iend = false;
    std::string idat;
    while (!have_iend) {
        if (data.size() - at < 12) fail("truncated at byte " + std::to_string(at) + " (no IEND chunk)");
        const std::uint32_t len = read_be32(data, at);
        if (len > 0x7FFFFFFFu || len > data.size() - at - 12)
            fail("chunk at byte " + std::to_string(at) + " declares " + std::to_string(len) + " bytes, the file has " +
                 std::to_string(data.size() - at - 12) + " left");
        const std::string_view type = data.substr(at + 4, 4), body = data.substr(at + 8, len);
        if (crc32(data.substr(at + 4, 4 + len)) != read_be32(data, at + 8 + len))
            fail("CRC mismatch in chunk '" + std::string(type) + "' at byte " + std::to_string(at));
        if (!have_ihdr && type != "IHDR") fail("first chunk is '" + std::string(type) + "', expected IHDR");
        if (type == "IHDR") {
            if (have_ihdr || len != 13) fail("IHDR repeated or not 13 bytes");
            have_ihdr = true;
            w = read_be32(body, 0);
            h = read_be32(body, 4);
            const unsigned depth = static_cast<unsigned char>(body[8]), color = static_cast<unsigned char>(body[9]);
            interlace = static_cast<unsigned char>(body[12]);
            check_image_size(what, w, h);
            if (depth != 8 || color != 2) {
                const int comp = color == 0 ? 1 : color == 4 ? 2 : color == 6 ? 4 : 3;  // 3: RGB or palette
                throw format_error(what + ": " + std::to_string(comp) + " channel" + (comp == 1 ? "" : "s") +
                                   (depth == 16 ? " of 16 bits" : "") + " found, expected 3 (8-bit RGB) (PNG colour type " +
                                   std::to_string(color) + ", bit depth " + std::to_string(depth) + ")");
            }
            if (body[10] != 0 || body[11] != 0 || interlace > 1) fail("unknown compression, filter or interlace method");
        } else if (type == "IDAT") {
            idat.append(body);
        } else if (type == "IEND") {
            have_iend = true;
        }
        at += 12 + len;
    }
    // Bytes of the filtered scanlines: 1 filter byte + 3 w bytes per row (per pass row when Adam7-interlaced).
    std::size_t expected = 0;
    if (interlace == 0) {
        expected = std::size_t{h} * (1 + 3 * std::size_t{w});
    } else {
        constexpr unsigned xs[] = {0, 4, 0, 2, 0, 1, 0}, ys[] = {0, 0, 4, 0, 2, 0, 1}, dx[] = {8, 8, 4, 4, 2, 2, 1},
                           dy[] = {8, 8, 8, 4, 4, 2, 2};
        for (int p = 0; p < 7; ++p) {
            const std::size_t pw = w > xs[p] ? (w - xs[p] + dx[p] - 1) / dx[p] : 0;
            const std::size_t ph = h > ys[p] ? (h - ys[p] + dy[p] - 1) / dy[p] : 0;
            if (pw && ph) expected += ph * (1 + 3 * pw);
        }
    }
    if (idat.size() < 6) fail("IDAT holds " + std::to_string(idat.size()) + " bytes, too few for a zlib stream");
    if (idat.size() > static_cast<std::size_t>(INT_MAX)) fail("IDAT stream is too large");
    // One byte of headroom: a stream that fills it decompresses to more than the header declares.
    std::unique_ptr<char[]> raw(new char[expected + 1]);
    const int got = stbi_zlib_decode_buffer(raw.get(), static_cast<int>(expected + 1), idat.data(), static_cast<int>(idat.size()));
    if (got < 0 || static_cast<std::size_t>(got) != expected)
        fail("IDAT stream is corrupt or does not decompress to the " + std::to_string(expected) + " bytes of a " +
             std::to_string(w) + "x" + std::to_string(h) + " image" +
             (got >= 0 ? " (found " + std::to_string(got) + ")" : std::string()));
    if (adler32(reinterpret_cast<const unsigned char*>(raw.get()), expected) != read_be32(idat, idat.size() - 4))
        fail("Adler-32 mismatch in the IDAT stream");
}

/// Checks a BMP before stb_image sees it (stb fills missing pixel data with zeros and takes a negative
/// compression field for none): only uncompressed 24- or 32-bit BMPs with every row present are read.
inline void check_bmp(std::string_view data, const std::string& what)
{
    if (data.size() < 54)
        throw format_error(what + ": truncated BMP: " + std::to_string(data.size()) + " bytes, a header needs 54");
    const std::uint32_t declared = read_le32(data, 2), offset = read_le32(data, 10), header = read_le32(data, 14);
    // width and height are signed (a negative height is a top-down BMP)
    const std::int64_t sw = static_cast<std::int32_t>(read_le32(data, 18)), sh = static_cast<std::int32_t>(read_le32(data, 22));
    if (sw <= 0 || sh == 0)
        throw format_error(what + ": BMP size " + std::to_string(sw) + "x" + std::to_string(sh) + " is empty");
    const std::size_t w = static_cast<std::size_t>(sw), h = static_cast<std::size_t>(sh < 0 ? -sh : sh);
    check_image_size(what, w, h);
    const unsigned bpp = static_cast<unsigned char>(data[28]) | static_cast<unsigned>(static_cast<unsigned char>(data[29])) << 8;
    const std::uint32_t compression = read_le32(data, 30);
    // 32-bit BMPs may carry bit-field masks (compression 3); the row layout is the same
    if (header < 40 || (compression != 0 && !(compression == 3 && bpp == 32)) || (bpp != 24 && bpp != 32))
        throw format_error(what + ": BMP with a " + std::to_string(header) + "-byte header, " + std::to_string(bpp) +
                           " bits per pixel and compression " + std::to_string(compression) +
                           ", expected an uncompressed 24- or 32-bit BMP (40-byte header or larger)");
    if (offset < 14 + std::size_t{header})
        throw format_error(what + ": BMP pixel data offset " + std::to_string(offset) + " lies inside the header");
    const std::size_t stride = (w * (bpp / 8) + 3) / 4 * 4;
    const std::size_t need = std::max<std::size_t>(declared, std::size_t{offset} + stride * h);
    if (data.size() < need)
        throw format_error(what + ": truncated BMP: " + std::to_string(data.size()) + " bytes, header needs " +
                           std::to_string(need));
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
    // handemo's own checks first: stb's header scan neither checks nor explains enough
    if (is_bmp) detail::check_bmp(data, what);
    if (is_png) detail::check_png(data, what);
    int w = 0, h = 0, comp = 0;
    if (!stbi_info_from_memory(buf, len, &w, &h, &comp))
        throw format_error(what + ": corrupt " + (is_png ? "PNG" : "BMP") + " header: " + detail::stb_reason());
    if (w <= 0 || h <= 0) throw format_error(what + ": size " + std::to_string(w) + "x" + std::to_string(h) + " is empty");
    detail::check_image_size(what, static_cast<std::size_t>(w), static_cast<std::size_t>(h));
    const bool deep = stbi_is_16_bit_from_memory(buf, len) != 0;
    if (comp != 3 || deep)
        throw format_error(what + ": " + std::to_string(comp) + " channel" + (comp == 1 ? "" : "s") +
                           (deep ? " of 16 bits" : "") + " found, expected 3 (8-bit RGB)");
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
