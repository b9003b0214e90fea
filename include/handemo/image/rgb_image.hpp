// An 8-bit RGB image held in memory, row-major: the container of the hand paper's motion images
// (Eq. 3 encodes 9 keyframes x 23 joints x 3 angles as a 9-row, 23-column RGB image; Eq. 6 decodes it).
// This header has no external dependency; reading and writing files is in handemo/image/io.hpp (stb).
#pragma once

#include <handemo/core/error.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace handemo {

/// @brief A row-major 8-bit RGB image: pixel (row, col) channel c is pixels[(row * width + col) * 3 + c].
struct rgb_image {
    std::size_t width = 0;
    std::size_t height = 0;
    std::vector<std::uint8_t> pixels;  ///< [height, width, 3]

    /// @brief A black image of the given size.
    static rgb_image make(std::size_t width, std::size_t height)
    {
        rgb_image im;
        im.width = width;
        im.height = height;
        im.pixels.assign(width * height * 3, 0);
        return im;
    }

    /// @brief Pointer to the 3 bytes (R, G, B) of pixel (row, col). No bounds check.
    std::uint8_t* at(std::size_t row, std::size_t col) noexcept { return pixels.data() + (row * width + col) * 3; }
    const std::uint8_t* at(std::size_t row, std::size_t col) const noexcept
    {
        return pixels.data() + (row * width + col) * 3;
    }
    bool empty() const noexcept { return width == 0 || height == 0; }

    /// @brief Checks that pixels holds height * width * 3 bytes.
    /// @throws shape_error naming `what`, the sizes found and expected.
    void validate(const std::string& what = "rgb_image") const
    {
        if (pixels.size() != width * height * 3)
            throw shape_error(what + ": pixel buffer holds " + std::to_string(pixels.size()) +
                              " bytes, expected height*width*3 = " + std::to_string(height) + "*" +
                              std::to_string(width) + "*3 = " + std::to_string(width * height * 3));
    }

    friend bool operator==(const rgb_image&, const rgb_image&) = default;
};

}  // namespace handemo
