// Tests of the rasteriser and the 5x7 font (render/canvas.hpp, render/font.hpp).
#include <handemo/render/canvas.hpp>
#include <handemo/render/font.hpp>

#include <doctest/doctest.h>

#include <set>

using namespace handemo;

namespace {
double coverage_sum(const canvas& cv)  // how much "ink" (black on white) the canvas holds, in pixels
{
    double s = 0;
    for (std::size_t y = 0; y < cv.height(); ++y)
        for (std::size_t x = 0; x < cv.width(); ++x) s += 1.0 - cv.at(x, y).r;
    return s;
}
}  // namespace

TEST_CASE("canvas: size checks, background and 8-bit conversion")
{
    CHECK_THROWS_AS(canvas(0, 10), value_error);
    CHECK_THROWS_AS(canvas(10, 1u << 16), value_error);
    canvas cv(4, 3, color::rgb8(10, 20, 30));
    const rgb_image im = cv.to_image();
    REQUIRE(im.width == 4);
    REQUIRE(im.height == 3);
    CHECK(im.at(2, 3)[0] == 10);
    CHECK(im.at(2, 3)[1] == 20);
    CHECK(im.at(2, 3)[2] == 30);
}

TEST_CASE("canvas: anti-aliased primitives cover their area")
{
    SUBCASE("a flat disc of radius 10 covers ~pi r^2 pixels")
    {
        canvas cv(40, 40);
        cv.fill_disc({20, 20}, 10, {0, 0, 0});
        CHECK(coverage_sum(cv) == doctest::Approx(3.14159265 * 100).epsilon(0.01));
        CHECK(cv.at(20, 20).r == 0.0f);   // centre fully covered
        CHECK(cv.at(2, 2).r == 1.0f);     // far corner untouched
        const float edge = cv.at(29, 20).r;  // pixel centre 29.5 is 0.5 px inside the rim at x = 30
        CHECK(edge >= 0.0f);
        CHECK(edge < 1.0f);
    }
    SUBCASE("a line of width 4 and length 20 covers ~ 20 x 4 + pi 2^2")
    {
        canvas cv(40, 40);
        cv.draw_line({10, 20}, {30, 20}, 4, {0, 0, 0});
        CHECK(coverage_sum(cv) == doctest::Approx(80 + 3.14159265 * 4).epsilon(0.02));
    }
    SUBCASE("a convex polygon (square given in any order) covers its area")
    {
        canvas cv(40, 40);
        const point2 sq[] = {{10, 10}, {30, 30}, {30, 10}, {10, 30}, {20, 20}};
        cv.fill_convex(sq, {0, 0, 0});
        CHECK(coverage_sum(cv) == doctest::Approx(400).epsilon(0.005));
        CHECK(canvas::convex_hull(sq).size() == 4);
    }
    SUBCASE("a lit capsule is shaded: brighter toward the light (upper left) than away from it")
    {
        canvas cv(60, 60);
        cv.draw_capsule({10, 30}, {50, 30}, 10, 10, {0.8f, 0.2f, 0.2f});
        CHECK(cv.at(30, 24).r > cv.at(30, 36).r);
        CHECK(cv.at(30, 30).r < 1.0f);
    }
}

TEST_CASE("font: 95 distinct glyphs, blank space, text boxes")
{
    std::set<std::array<std::uint8_t, 7>> seen;
    for (int ch = 33; ch <= 126; ++ch) {
        const auto& g = detail::font_5x7[static_cast<std::size_t>(ch - 32)];
        bool any = false;
        for (auto row : g) any = any || row != 0;
        CHECK_MESSAGE(any, "glyph ", ch, " is blank");
        CHECK_MESSAGE(seen.insert(g).second, "glyph ", ch, " duplicates another");
    }
    for (auto row : detail::font_5x7[0]) CHECK(row == 0);  // space
    CHECK(text_width("abc", 1) == 17);
    CHECK(text_width("abc", 2) == 34);
    CHECK(text_width("", 3) == 0);

    canvas cv(40, 40);
    draw_text(cv, 5, 6, "Hi", {0, 0, 0}, 2);
    // all ink inside [5, 5 + 22) x [6, 6 + 14)
    for (std::size_t y = 0; y < 40; ++y)
        for (std::size_t x = 0; x < 40; ++x)
            if (cv.at(x, y).r < 1.0f) {
                CHECK(x >= 5);
                CHECK(x < 27);
                CHECK(y >= 6);
                CHECK(y < 20);
            }
    CHECK(cv.at(5, 6).r == 0.0f);  // 'H' top-left pixel is set

    canvas rot(20, 40);
    draw_text(rot, 2, 30, "ab", {0, 0, 0}, 1, true);  // rotated: [2, 9) x [30 - 11, 30)
    double ink = 0;
    for (std::size_t y = 0; y < 40; ++y)
        for (std::size_t x = 0; x < 20; ++x)
            if (rot.at(x, y).r < 1.0f) {
                ink += 1;
                CHECK(x >= 2);
                CHECK(x < 9);
                CHECK(y >= 19);
                CHECK(y < 30);
            }
    CHECK(ink > 10);
}
