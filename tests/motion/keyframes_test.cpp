#include <handemo/motion/hand.hpp>
#include <handemo/motion/keyframes.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

using namespace handemo;

namespace {
// A smooth clip: every angle a different low-frequency sinusoid (one cycle over the clip at most).
clip smooth_clip(std::size_t frames, double fps = 60.0)
{
    clip c = clip::make(hand_skeleton(), frames, fps);
    for (std::size_t f = 0; f < frames; ++f) {
        const double t = static_cast<double>(f) / static_cast<double>(frames - 1);
        for (std::size_t j = 0; j < c.skel.size(); ++j)
            for (std::size_t a = 0; a < 3; ++a)
                c.angle(f, j, a) = 20.0 * std::sin(2 * std::numbers::pi * (0.5 + 0.5 * static_cast<double>(a)) * t * 0.8 +
                                                   0.3 * static_cast<double>(j)) + static_cast<double>(j);
    }
    return c;
}
}  // namespace

TEST_CASE("unwrap_angles removes 360-degree jumps and keeps small steps")
{
    clip c = clip::make(hand_skeleton(), 6, 30);
    const double track[] = {170, 178, -176, -170, 179, -181};  // passes 180 twice, last is 179 wrapped
    for (std::size_t f = 0; f < 6; ++f) {
        c.angle(f, 4, 1) = track[f];
        c.angle(f, 2, 0) = 10.0 * static_cast<double>(f);  // ordinary motion, untouched
    }
    unwrap_angles(c);
    const double expect[] = {170, 178, 184, 190, 179, 179};
    for (std::size_t f = 0; f < 6; ++f) {
        CHECK(c.angle(f, 4, 1) == doctest::Approx(expect[f]));
        CHECK(c.angle(f, 2, 0) == doctest::Approx(10.0 * static_cast<double>(f)));
    }
}

TEST_CASE("extract_keyframes: uniform times, exact frames, any J and K, runtime K")
{
    clip c = smooth_clip(161);  // (161-1)/(9-1) = 20: every keyframe is an exact frame
    const auto k = extract_keyframes<9>(c);
    CHECK(k.count() == 9);
    CHECK(k.joints == 23);
    CHECK(k.source_frames == 161);
    CHECK(k.fps == 60.0);
    CHECK(k.duration == doctest::Approx(161.0 / 60.0));
    for (std::size_t i = 0; i < 9; ++i)
        for (std::size_t j = 0; j < 23; ++j)
            for (std::size_t a = 0; a < 3; ++a) CHECK(k.at(i, j, a) == doctest::Approx(c.angle(i * 20, j, a)));
    // Fractional positions are linear interpolations: 10 frames, K = 4 -> positions 0, 3, 6, 9 exact;
    // K = 7 -> position 1.5 between frames 1 and 2.
    clip d = smooth_clip(10);
    const auto k7 = extract_keyframes<dynamic_keyframes>(d, 7);
    CHECK(k7.count() == 7);
    CHECK(k7.at(1, 5, 2) == doctest::Approx(0.5 * (d.angle(1, 5, 2) + d.angle(2, 5, 2))));
    CHECK(k7.at(6, 5, 2) == doctest::Approx(d.angle(9, 5, 2)));
    CHECK_THROWS_AS(extract_keyframes<dynamic_keyframes>(d, 1), value_error);
    CHECK_THROWS_AS(extract_keyframes<9>(clip::make(hand_skeleton(), 1, 30)), value_error);
    // the error names the clip it was reading (the skeleton's name is the file a reader got it from)
    clip one = clip::make(hand_skeleton(), 1, 30);
    one.skel.name = "one_frame.bvh";
    CHECK_THROWS_WITH_AS(extract_keyframes<9>(one), doctest::Contains("one_frame.bvh has 1 frames, expected at least 2"), value_error);
    // Wrapped input gives the unwrapped keyframes.
    clip w = clip::make(hand_skeleton(), 9, 30);
    for (std::size_t f = 0; f < 9; ++f) w.angle(f, 0, 1) = std::remainder(150.0 + 10.0 * static_cast<double>(f), 360.0);
    const auto kw = extract_keyframes<9>(w);
    CHECK(kw.at(8, 0, 1) == doctest::Approx(230.0));
    // keyframe_cast between static and dynamic counts.
    const auto kd = keyframe_cast<dynamic_keyframes>(k);
    CHECK(kd.count() == 9);
    CHECK(keyframe_cast<9>(kd).angles == k.angles);
    CHECK_THROWS_AS(keyframe_cast<5>(kd), shape_error);
}

TEST_CASE("reconstruct: exact at keyframes, close to a smooth original, all interpolants")
{
    clip c = smooth_clip(161);
    const auto k = extract_keyframes<9>(c);
    for (auto method : {interpolation::catmull_rom, interpolation::natural_spline, interpolation::linear}) {
        const clip r = reconstruct(k, c.skel, 161, 60.0, {}, method);
        CHECK(r.frames == 161);
        CHECK(r.fps == 60.0);
        CHECK_NOTHROW(r.validate());
        double max_err = 0, max_key = 0;
        for (std::size_t f = 0; f < 161; ++f)
            for (std::size_t i = 0; i < 23 * 3; ++i) {
                const double e = std::abs(r.angles[f * 69 + i] - c.angles[f * 69 + i]);
                max_err = std::max(max_err, e);
                if (f % 20 == 0) max_key = std::max(max_key, e);
            }
        CHECK(max_key < 1e-9);
        // Signals of amplitude 20 deg with <= 0.8 cycles per 8 keyframe intervals.
        if (method == interpolation::linear) CHECK(max_err < 2.5);
        else if (method == interpolation::catmull_rom) CHECK(max_err < 2.0);
        else CHECK(max_err < 1.5);
        MESSAGE("reconstruct error (deg), method " << static_cast<int>(method) << ": " << max_err);
    }
    // Another length and a root translation track.
    std::vector<double> tr(50 * 3);
    for (std::size_t f = 0; f < 50; ++f) tr[f * 3 + 2] = static_cast<double>(f);
    const clip r = reconstruct(k, c.skel, 50, 30.0, tr);
    CHECK(r.frames == 50);
    CHECK(r.position(49, 0, 2) == 49.0);
    CHECK(r.position(49, 1, 1) == doctest::Approx(c.skel.joints[1].offset[1]));
    CHECK(r.angle(49, 7, 0) == doctest::Approx(k.at(8, 7, 0)));
    CHECK_THROWS_AS(reconstruct(k, c.skel, 50, 30.0, std::span<const double>(tr.data(), 10)), shape_error);
    skeleton small = c.skel;
    small.joints.pop_back();
    CHECK_THROWS_AS(reconstruct(k, small, 50, 30.0), shape_error);
    CHECK_THROWS_AS(reconstruct(k, c.skel, 1, 30.0), value_error);
}

TEST_CASE("extract_keyframes_aligned: DTW undoes a time warp")
{
    // Reference: uniform sinusoid over 121 frames; c: the same motion with a strongly non-uniform time map
    // (slow start, fast end) over 90 frames. Uniform keyframes of c differ; aligned ones match.
    const std::size_t m = 121, n = 90;
    clip ref = clip::make(hand_skeleton(), m, 60), c = clip::make(hand_skeleton(), n, 60);
    auto motion = [](double s, std::size_t j, std::size_t a) {
        return 30.0 * std::sin(2 * std::numbers::pi * s + 0.2 * static_cast<double>(j + a)) + 40.0 * s;
    };
    for (std::size_t f = 0; f < m; ++f)
        for (std::size_t j = 0; j < 23; ++j)
            for (std::size_t a = 0; a < 3; ++a) ref.angle(f, j, a) = motion(static_cast<double>(f) / (m - 1), j, a);
    for (std::size_t f = 0; f < n; ++f) {
        const double u = static_cast<double>(f) / (n - 1);
        for (std::size_t j = 0; j < 23; ++j)
            for (std::size_t a = 0; a < 3; ++a) c.angle(f, j, a) = motion(u * u, j, a);
    }
    const auto kr = extract_keyframes<9>(ref);
    const auto ku = extract_keyframes<9>(c);
    const auto ka = extract_keyframes_aligned<9>(c, ref);
    double err_u = 0, err_a = 0;
    for (std::size_t i = 0; i < kr.angles.size(); ++i) {
        err_u = std::max(err_u, std::abs(ku.angles[i] - kr.angles[i]));
        err_a = std::max(err_a, std::abs(ka.angles[i] - kr.angles[i]));
    }
    MESSAGE("uniform keyframe error " << err_u << " deg, DTW-aligned " << err_a << " deg");
    CHECK(err_u > 15.0);
    CHECK(err_a < 3.0);
    CHECK(ka.source_frames == n);
    // Aligning a clip to itself gives its uniform keyframes.
    const auto ks = extract_keyframes_aligned<9>(ref, ref);
    for (std::size_t i = 0; i < kr.angles.size(); ++i) CHECK(ks.angles[i] == doctest::Approx(kr.angles[i]));
    skeleton small = ref.skel;
    small.joints.pop_back();
    clip bad = clip::make(small, 10, 60);
    CHECK_THROWS_AS(extract_keyframes_aligned<9>(bad, ref), shape_error);
}
