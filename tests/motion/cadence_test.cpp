#include <handemo/motion/cadence.hpp>
#include <handemo/motion/hand.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <string>

using namespace handemo;

namespace {
constexpr double cadence_two_pi = 2 * std::numbers::pi;

// `cycles` cycles of a movement of period `period` seconds: every channel a sine of amplitude `amp` (its own
// phase), plus, when `tremor` > 0, a 9 Hz sine of that amplitude on every third channel.
clip cadence_cycles(double period, double cycles, double amp = 30.0, double fps = 60.0, double tremor = 0.0)
{
    const auto frames = static_cast<std::size_t>(std::lround(cycles * period * fps)) + 1;
    clip c = clip::make(hand_skeleton(), frames, fps);
    const std::size_t C = c.skel.size() * 3;
    for (std::size_t f = 0; f < frames; ++f) {
        const double t = static_cast<double>(f) / fps;
        for (std::size_t ch = 0; ch < C; ++ch) {
            double v = 10.0 + amp * std::sin(cadence_two_pi * t / period + 0.3 * static_cast<double>(ch));
            if (tremor > 0 && ch % 3 == 0) v += tremor * std::sin(cadence_two_pi * 9.0 * t);
            c.angles[f * C + ch] = v;
        }
    }
    return c;
}
}  // namespace

TEST_CASE("cadence_time is half the period, whatever the number of cycles")
{
    const double two = cadence_time(cadence_cycles(1.2, 2)), five = cadence_time(cadence_cycles(1.2, 5)), one = cadence_time(cadence_cycles(1.2, 1));
    CHECK(two == doctest::Approx(0.6).epsilon(0.02));
    CHECK(five == doctest::Approx(two).epsilon(0.01));
    CHECK(one == doctest::Approx(two).epsilon(0.02));
    // the duration counts the cycles, the cadence does not
    CHECK(cadence_cycles(1.2, 5).duration() / cadence_cycles(1.2, 2).duration() == doctest::Approx(2.5).epsilon(0.01));
}

TEST_CASE("cadence_time scales with the tempo and ignores the amplitude and a fast tremor")
{
    const double base = cadence_time(cadence_cycles(1.0, 3));
    CHECK(cadence_time(cadence_cycles(1.5, 3)) / base == doctest::Approx(1.5).epsilon(0.01));  // 1.5x slower
    CHECK(cadence_time(cadence_cycles(0.5, 3)) / base == doctest::Approx(0.5).epsilon(0.02));  // twice as fast
    CHECK(cadence_time(cadence_cycles(1.0, 3, 90.0)) == doctest::Approx(base).epsilon(1e-9));  // 3x the excursions: unchanged
    // a 5-degree 9 Hz tremor on every third channel of a 30-degree 1 Hz movement: the 0.2 s smoothing leaves it out;
    // unsmoothed it makes the clip read about 13% faster
    CHECK(cadence_time(cadence_cycles(1.0, 3, 30.0, 60.0, 5.0)) == doctest::Approx(base).epsilon(0.01));
    CHECK(cadence_time(cadence_cycles(1.0, 3, 30.0, 60.0, 5.0), 0.0) < 0.9 * base);
}

TEST_CASE("cadence_time refuses a clip without a cadence, naming it")
{
    clip still = clip::make(hand_skeleton(), 30, 30.0);
    still.skel.name = "still-hand";
    CHECK_THROWS_WITH_AS(cadence_time(still), doctest::Contains("still-hand does not move"), value_error);
    clip two = cadence_cycles(1.0, 0.03);
    REQUIRE(two.frames == 3);
    two.frames = 2, two.angles.resize(2 * two.skel.size() * 3), two.positions.resize(two.angles.size());
    CHECK_THROWS_WITH_AS(cadence_time(two), doctest::Contains("2 frames"), value_error);
    clip nan = cadence_cycles(1.0, 2);
    nan.angles[5] = std::nan("");
    CHECK_THROWS_AS(cadence_time(nan), value_error);
    CHECK_THROWS_WITH_AS(cadence_time(cadence_cycles(1.0, 2), -1.0), doctest::Contains("smoothing"), value_error);
}
