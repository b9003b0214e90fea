// A filmstrip along a circumplex path (render/circumplex_strip.hpp): the filmstrip under a band of small
// circumplexes, each column's target point drawn where its valence and arousal put it.
#include <handemo/motion/synth.hpp>
#include <handemo/render/circumplex_strip.hpp>

#include <doctest/doctest.h>

#include <optional>
#include <utility>
#include <vector>

using namespace handemo;

TEST_CASE("circumplex filmstrip: an inset above each column with its target point")
{
    const std::vector<clip> clips = {synthesize(hand_motion::pointing, emotion::neutral, 0, 1, 30.0),
                                     synthesize(hand_motion::pointing, emotion::sad, 0, 1, 30.0)};
    filmstrip_options fo;
    fo.rows = 2;
    fo.cell_width = fo.cell_height = 100;
    const std::vector<label_point> labels = {{"neutral", 0.125, -0.3875}, {"sad", -0.725, -0.3775}};
    const rgb_image strip = render_filmstrip(clips, fo);
    const rgb_image im = render_circumplex_filmstrip(clips, {std::nullopt, std::pair{0.5, 0.5}}, labels, fo);
    const long gap = filmstrip_gap, side = 100, band = side + gap;
    REQUIRE(im.width == strip.width);
    REQUIRE(im.height == strip.height + static_cast<std::size_t>(band));
    // the filmstrip itself, unchanged below the band
    CHECK(std::equal(strip.pixels.begin(), strip.pixels.end(), im.pixels.begin() + static_cast<long>(band * im.width * 3)));
    const auto red = [&](long x, long y) {
        const std::uint8_t* p = im.pixels.data() + (static_cast<std::size_t>(y) * im.width + static_cast<std::size_t>(x)) * 3;
        return p[0] > 180 && p[1] < 90 && p[2] < 90;
    };
    // column 1's target (0.5, 0.5): the inset's centre plus 0.42 side times the point, y up
    const long x0 = gap + (100 + gap), cx = x0 + side / 2, cy = gap + side / 2;
    CHECK(red(cx + static_cast<long>(0.5 * 0.42 * side), cy - static_cast<long>(0.5 * 0.42 * side)));
    CHECK_FALSE(red(cx - static_cast<long>(0.5 * 0.42 * side), cy + static_cast<long>(0.5 * 0.42 * side)));
    // column 0 (no point): no inset, no red
    bool any = false;
    for (long y = 0; y < band; ++y)
        for (long x = gap; x < gap + 100; ++x) any = any || red(x, y);
    CHECK_FALSE(any);
    CHECK_THROWS_AS(render_circumplex_filmstrip(clips, {std::nullopt}, labels, fo), value_error);
}
