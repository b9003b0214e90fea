#include "helpers.hpp"

#include <doctest/doctest.h>
#include <handemo/metrics/compare.hpp>

#include <cmath>

using namespace handemo;
using namespace handemo::metrics;
using handemo::metrics::test::sine_clip;

TEST_CASE("keyframe_rmse of a constant offset is the offset; differences are wrapped")
{
    const clip a = sine_clip(61, 30, 20);
    CHECK(keyframe_rmse(a, a) == doctest::Approx(0.0));
    for (double off : {5.0, -12.5}) {
        const clip b = sine_clip(61, 30, 20, off);
        CHECK(keyframe_rmse(a, b) == doctest::Approx(std::abs(off)).epsilon(1e-9));
    }
    // a full turn is no difference, 350 degrees is 10
    CHECK(keyframe_rmse(a, sine_clip(61, 30, 20, 360.0)) == doctest::Approx(0.0).epsilon(1e-9));
    CHECK(keyframe_rmse(a, sine_clip(61, 30, 20, 350.0)) == doctest::Approx(10.0).epsilon(1e-9));
    // keyframes are uniform in time: the same motion at another frame count compares equal
    CHECK(keyframe_rmse(sine_clip(65, 30, 20), sine_clip(129, 60, 20)) == doctest::Approx(0.0).epsilon(1e-9));
    CHECK(wrap_degrees(190) == doctest::Approx(-170));
    CHECK(wrap_degrees(-180) == doctest::Approx(180));
}

TEST_CASE("keyframe_rmse refuses clips of different skeletons")
{
    clip a = sine_clip(31, 30, 10);
    clip b = a;
    b.skel.joints.pop_back();
    b.angles.resize(b.frames * b.skel.size() * 3);
    b.positions.resize(b.angles.size());
    CHECK_THROWS_AS(keyframe_rmse(a, b), shape_error);
}

TEST_CASE("range of motion and speed of a scaled and a time-stretched clip")
{
    // one sine cycle sampled so that its extremes are frames: ROM = 2 amp exactly
    const clip a = sine_clip(81, 40, 10);
    const clip s = sine_clip(81, 40, 25);
    CHECK(range_of_motion(s) / range_of_motion(a) == doctest::Approx(2.5).epsilon(1e-9));
    CHECK(mean_speed(s) / mean_speed(a) == doctest::Approx(2.5).epsilon(1e-9));
    // the same motion over twice the duration (same fps): same ROM, half the speed
    const clip slow = sine_clip(161, 40, 10);
    CHECK(range_of_motion(slow) == doctest::Approx(range_of_motion(a)).epsilon(1e-3));
    CHECK(mean_speed(slow) / mean_speed(a) == doctest::Approx(0.5).epsilon(1e-3));
    // measured on the keyframe view the ratios are the same
    const auto ca = measure(a), cs = measure(s), cslow = measure(slow);
    CHECK(ratio(cs.range_of_motion, ca.range_of_motion, "rom") == doctest::Approx(2.5).epsilon(1e-9));
    CHECK(ratio(cslow.speed, ca.speed, "speed") == doctest::Approx(0.5).epsilon(1e-3));
    CHECK(cslow.duration == doctest::Approx(161.0 / 40.0));  // frames / fps
    // a ramp of 2 degrees per frame at 30 fps moves at 60 deg/s
    clip r = clip::make(hand_skeleton(), 10, 30);
    for (std::size_t i = 0; i < r.angles.size(); ++i) r.angles[i] = 2.0 * static_cast<double>(i / (r.skel.size() * 3));
    CHECK(mean_speed(r) == doctest::Approx(60.0));
    CHECK(range_of_motion(r) == doctest::Approx(18.0));
    CHECK(log_ratio_error(2.0, 1.0) == doctest::Approx(std::log(2.0)));
    CHECK(log_ratio_error(0.5, 1.0) == doctest::Approx(std::log(2.0)));
}

TEST_CASE("range of motion counts a channel that unwraps over several turns as at most 360 degrees")
{
    // a channel spinning 5 full turns in 18-degree steps: unwrapped it spans 1800 degrees; within 180 of the
    // first frame the samples cover -162 .. 180, a range of 342
    clip c = clip::make(hand_skeleton(), 101, 30);
    const std::size_t J3 = c.skel.size() * 3;
    for (std::size_t f = 0; f < c.frames; ++f) c.angles[f * J3] = 18.0 * static_cast<double>(f);
    CHECK(range_of_motion(c) * static_cast<double>(J3) == doctest::Approx(342.0));
    // a swing of +-30 about 170 degrees (crossing +-180 in the file) is 60 degrees
    clip s = clip::make(hand_skeleton(), 61, 30);
    for (std::size_t f = 0; f < s.frames; ++f)
        s.angles[f * J3] = wrap_degrees(170.0 + 30.0 * std::sin(2 * 3.141592653589793 * static_cast<double>(f) / 60.0));
    CHECK(range_of_motion(s) * static_cast<double>(J3) == doctest::Approx(60.0).epsilon(1e-3));
}

TEST_CASE("keyframe view keeps the keyframes; ratios to a still input are refused")
{
    const clip a = sine_clip(81, 40, 10, 3.0, 2.0);
    const clip v = keyframe_view(a);
    CHECK(v.frames == a.frames);
    CHECK(keyframe_rmse(a, v) == doctest::Approx(0.0).epsilon(1e-9));
    const clip still = clip::make(hand_skeleton(), 20, 30);
    CHECK(range_of_motion(still) == 0.0);
    CHECK_THROWS_AS(ratio(1.0, range_of_motion(still), "range of motion"), value_error);
    clip one = clip::make(hand_skeleton(), 1, 30);
    CHECK_THROWS_AS(mean_speed(one), value_error);
}

TEST_CASE("duration ratio error is |log(duration out / duration real)|, whatever the frame rates")
{
    const clip real = sine_clip(61, 30, 20);  // 61 frames at 30 fps
    CHECK(duration_error(real, real) == 0.0);
    // twice as long at another frame rate: 244 frames at 60 fps
    CHECK(duration_error(sine_clip(244, 60, 20), real) == doctest::Approx(std::log(2.0)));
    // half as long: the same error, over- and undershoot alike
    CHECK(duration_error(sine_clip(61, 60, 20), real) == doctest::Approx(std::log(2.0)));
    CHECK(duration_error(sine_clip(91, 30, 20), real) == doctest::Approx(std::abs(std::log(91.0 / 61.0))));
    // identity keeps the input's duration: its error is |log(d_in / d_real)|
    const clip in = sine_clip(40, 30, 20);
    CHECK(duration_error(in, real) == doctest::Approx(std::abs(std::log(in.duration() / real.duration()))));
}
