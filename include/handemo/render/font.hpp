// The built-in 5x7 bitmap font of handemo's pictures: ASCII 32-126, one glyph per 6x8 cell (one column
// and one row of spacing), drawn at an integer scale, horizontally or rotated 90 degrees counter-clockwise
// (reading bottom to top, for the joint names along the columns of a motion image, Figure 3 of the hand
// paper). The glyph table is written out below as pictures ('#' set, '.' clear), 16 glyphs per block,
// and turned into bit rows at compile time. Characters outside 32-126 draw as a hollow box.
#pragma once

#include <handemo/render/canvas.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string_view>

namespace handemo {
namespace detail {

// Blocks of 16 glyphs: 32-47 ( !"#$%&'()*+,-./), 48-63 (0-9:;<=>?), 64-79 (@A-O), 80-95 (P-Z[\]^_),
// 96-111 (`a-o), 112-127 (p-z{|}~, then the box used for unknown characters).
inline constexpr std::string_view font_5x7_picture = R"(
..... ..#.. .#.#. .#.#. ..#.. ##... .##.. ..#.. ...#. .#... ..... ..... ..... ..... ..... .....
..... ..#.. .#.#. .#.#. .#### ##..# #..#. ..#.. ..#.. ..#.. ..#.. ..#.. ..... ..... ..... ....#
..... ..#.. ..... ##### #.#.. ...#. #.#.. ..... .#... ...#. #.#.# ..#.. ..... ..... ..... ...#.
..... ..#.. ..... .#.#. .###. ..#.. .#... ..... .#... ...#. .###. ##### ..... ##### ..... ..#..
..... ..#.. ..... ##### ..#.# .#... #.#.# ..... .#... ...#. #.#.# ..#.. .##.. ..... ..... .#...
..... ..... ..... .#.#. ####. #..## #..#. ..... ..#.. ..#.. ..#.. ..#.. ..#.. ..... .##.. #....
..... ..#.. ..... .#.#. ..#.. ...## .##.# ..... ...#. .#... ..... ..... .#... ..... .##.. .....

.###. ..#.. .###. ##### ...#. ##### ..##. ##### .###. .###. ..... ..... ...#. ..... .#... .###.
#...# .##.. #...# ...#. ..##. #.... .#... ....# #...# #...# .##.. .##.. ..#.. ..... ..#.. #...#
#..## ..#.. ....# ..#.. .#.#. ####. #.... ...#. #...# #...# .##.. .##.. .#... ##### ...#. ....#
#.#.# ..#.. ...#. ...#. #..#. ....# ####. ..#.. .###. .#### ..... ..... #.... ..... ....# ...#.
##..# ..#.. ..#.. ....# ##### ....# #...# .#... #...# ....# .##.. .##.. .#... ##### ...#. ..#..
#...# ..#.. .#... #...# ...#. #...# #...# .#... #...# ...#. .##.. ..#.. ..#.. ..... ..#.. .....
.###. .###. ##### .###. ...#. .###. .###. .#... .###. .##.. ..... .#... ...#. ..... .#... ..#..

.###. .###. ####. .###. ###.. ##### ##### .###. #...# .###. ..### #...# #.... #...# #...# .###.
#...# #...# #...# #...# #..#. #.... #.... #...# #...# ..#.. ...#. #..#. #.... ##.## #...# #...#
....# #...# #...# #.... #...# #.... #.... #.... #...# ..#.. ...#. #.#.. #.... #.#.# ##..# #...#
.##.# ##### ####. #.... #...# ####. ####. #.### ##### ..#.. ...#. ##... #.... #.#.# #.#.# #...#
#.#.# #...# #...# #.... #...# #.... #.... #...# #...# ..#.. ...#. #.#.. #.... #...# #..## #...#
#.#.# #...# #...# #...# #..#. #.... #.... #...# #...# ..#.. #..#. #..#. #.... #...# #...# #...#
.###. #...# ####. .###. ###.. ##### #.... .#### #...# .###. .##.. #...# ##### #...# #...# .###.

####. .###. ####. .#### ##### #...# #...# #...# #...# #...# ##### .###. ..... .###. ..#.. .....
#...# #...# #...# #.... ..#.. #...# #...# #...# #...# #...# ....# .#... #.... ...#. .#.#. .....
#...# #...# #...# #.... ..#.. #...# #...# #...# .#.#. .#.#. ...#. .#... .#... ...#. #...# .....
####. #...# ####. .###. ..#.. #...# #...# #.#.# ..#.. ..#.. ..#.. .#... ..#.. ...#. ..... .....
#.... #.#.# #.#.. ....# ..#.. #...# #...# #.#.# .#.#. ..#.. .#... .#... ...#. ...#. ..... .....
#.... #..#. #..#. ....# ..#.. #...# .#.#. #.#.# #...# ..#.. #.... .#... ....# ...#. ..... .....
#.... .##.# #...# ####. ..#.. .###. ..#.. .#.#. #...# ..#.. ##### .###. ..... .###. ..... #####

.#... ..... #.... ..... ....# ..... ..##. ..... #.... ..#.. ...#. #.... .##.. ..... ..... .....
..#.. ..... #.... ..... ....# ..... .#..# .#### #.... ..... ..... #.... ..#.. ..... ..... .....
..... .###. #.##. .###. .##.# .###. .#... #...# #.##. .##.. ..##. #..#. ..#.. ##.#. #.##. .###.
..... ....# ##..# #.... #..## #...# ###.. #...# ##..# ..#.. ...#. #.#.. ..#.. #.#.# ##..# #...#
..... .#### #...# #.... #...# ##### .#... .#### #...# ..#.. ...#. ##... ..#.. #.#.# #...# #...#
..... #...# #...# #...# #...# #.... .#... ....# #...# ..#.. #..#. #.#.. ..#.. #...# #...# #...#
..... .#### ####. .###. .#### .###. .#... .###. #...# .###. .##.. #..#. .###. #...# #...# .###.

..... ..... ..... ..... .#... ..... ..... ..... ..... ..... ..... ...## ..#.. ##... ..... #####
..... ..... ..... ..... .#... ..... ..... ..... ..... ..... ..... ..#.. ..#.. ..#.. ..... #...#
####. .##.# #.##. .#### ###.. #...# #...# #...# #...# #...# ##### ..#.. ..#.. ..#.. .#... #...#
#...# #..## ##..# #.... .#... #...# #...# #...# .#.#. #...# ...#. .#... ..#.. ...#. #.#.# #...#
####. .#### #.... .###. .#... #...# #...# #.#.# ..#.. .#### ..#.. ..#.. ..#.. ..#.. ...#. #...#
#.... ....# #.... ....# .#..# #..## .#.#. #.#.# .#.#. ....# .#... ..#.. ..#.. ..#.. ..... #...#
#.... ....# #.... ####. ..##. .##.# ..#.. .#.#. #...# .###. ##### ...## ..#.. ##... ..... #####
)";

/// 96 glyphs x 7 rows; bit 4 of a row is the leftmost pixel.
using font_table = std::array<std::array<std::uint8_t, 7>, 96>;

consteval font_table make_font_table()
{
    font_table t{};
    std::size_t pos = 1;  // skip the leading newline
    for (std::size_t block = 0; block < 6; ++block) {
        for (std::size_t row = 0; row < 7; ++row) {
            for (std::size_t g = 0; g < 16; ++g) {
                std::uint8_t bits = 0;
                for (std::size_t col = 0; col < 5; ++col)
                    bits = static_cast<std::uint8_t>((bits << 1) | (font_5x7_picture[pos++] == '#' ? 1 : 0));
                t[block * 16 + g][row] = bits;
                ++pos;  // the space between glyphs, or the newline after the last one
            }
        }
        ++pos;  // blank line between blocks
    }
    return t;
}

inline constexpr font_table font_5x7 = make_font_table();
static_assert(font_5x7['A' - 32][3] == 0b11111, "font: glyph 'A' row 3 should be the crossbar 11111");
static_assert(font_5x7['|' - 32][6] == 0b00100, "font: glyph '|' row 6 should be 00100");

}  // namespace detail

/// Glyph cell width and height in font pixels (5x7 glyph plus spacing).
inline constexpr int font_advance = 6, font_line_height = 8;

/// @brief Width in pixels of `text` drawn at `scale` (no trailing spacing column).
inline long text_width(std::string_view text, int scale = 1) noexcept
{
    return text.empty() ? 0 : static_cast<long>(text.size()) * font_advance * scale - scale;
}

/// @brief Height in pixels of one line of text at `scale` (the 7 glyph rows).
inline long text_height(int scale = 1) noexcept { return 7L * scale; }

/// @brief Draws `text` with its top-left corner at (x, y), each font pixel a scale x scale block.
/// @param rotated when true the text is rotated 90 degrees counter-clockwise: it reads bottom to top,
///        starts at (x, y) as its bottom-left corner and occupies [x, x + 7 scale) x (y - width, y].
inline void draw_text(canvas& cv, long x, long y, std::string_view text, color c, int scale = 1,
                      bool rotated = false) noexcept
{
    if (scale < 1) scale = 1;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const auto ch = static_cast<unsigned char>(text[i]);
        const auto& glyph = detail::font_5x7[(ch >= 32 && ch <= 126) ? ch - 32 : 95];
        const long pen = static_cast<long>(i) * font_advance * scale;
        for (int row = 0; row < 7; ++row) {
            for (int col = 0; col < 5; ++col) {
                if (!((glyph[static_cast<std::size_t>(row)] >> (4 - col)) & 1)) continue;
                // unrotated: pixel (pen + col, row); rotated CCW: text x runs up (-y), text y runs right (+x)
                const long px = rotated ? x + row * scale : x + pen + col * scale;
                const long py = rotated ? y - 1 - (pen + col * scale) - (scale - 1) : y + row * scale;
                cv.fill_rect(px, py, px + scale, py + scale, c);
            }
        }
    }
}

}  // namespace handemo
