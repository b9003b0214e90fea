// Tests of filmstrip animations (render/animation.hpp): output-frame timing follows the viewer page's rules
// (real time, each clip at its own rate, or normalised time), frame 0 is the one-row filmstrip pixel for
// pixel, and bad input is refused naming the clip. The GIF file itself: tests/gif/gif_test.cpp.
#include "helpers.hpp"

#include <handemo/render.hpp>

#include <doctest/doctest.h>

#include <vector>

using namespace handemo;

namespace {

animation_options two_clip_options()
{
    animation_options o;
    o.strip.cell_width = o.strip.cell_height = 120;
    o.strip.titles = {"hand", "body"};
    return o;
}

}  // namespace

TEST_CASE("animation: timing follows the viewer's rules and frame 0 is the one-row filmstrip")
{
    const std::vector<clip> clips{test::flexing_hand(40), test::stick_body(20)};
    animation_options o = two_clip_options();
    const filmstrip_animation a(clips, o);
    CHECK(a.fps() == doctest::Approx(30));
    CHECK(a.duration() == doctest::Approx(40.0 / 30.0));
    CHECK(a.frame_count() == 40);
    CHECK(a.clip_frames(25) == std::vector<std::size_t>{25, 19});  // the shorter clip holds its last frame
    filmstrip_options fo = o.strip;
    fo.rows = 1;
    CHECK(a.frame(0) == render_filmstrip(clips, fo));
    o.normalised_time = true;
    const filmstrip_animation n(clips, o);
    CHECK(n.clip_frames(39) == std::vector<std::size_t>{38, 19});  // t = 39/30 of T = 40/30
    o.normalised_time = false;
    o.fps = 12;
    const filmstrip_animation slow(clips, o);
    CHECK(slow.frame_count() == 16);  // ceil(1.333 * 12)
    CHECK(slow.clip_frames(5) == std::vector<std::size_t>{12, 12});
    std::vector<clip> bad = clips;
    bad[1] = clip::make(bad[1].skel, 0, 30);
    o.strip.titles = {"hand", "empty.bvh"};
    CHECK_THROWS_WITH_AS(filmstrip_animation(bad, o), doctest::Contains("empty.bvh"), value_error);
    CHECK_THROWS_AS(filmstrip_animation(std::vector<clip>{}, o), value_error);
}
