// The joint lag (stargan/lag.hpp): the keyframe shift per joint, the fit that recovers a planted lag, and the
// leave-one-content-out check that refuses a lag that does not carry over.
#include <doctest/doctest.h>
#include <handemo/stargan/lag.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

using namespace handemo;

namespace {

keyframes<9> ramp_keys(std::size_t joints)
{
    auto k = keyframes<9>::make(joints);
    for (std::size_t i = 0; i < 9; ++i)
        for (std::size_t j = 0; j < joints; ++j)
            for (std::size_t c = 0; c < 3; ++c) k.at(i, j, c) = 10.0 * double(i * i) + 100.0 * double(j) + double(c);
    return k;
}

/// A joint's curve read at s (linear between keyframes, clamped): what shift_joints() computes, out of place.
double curve_at(const keyframes<9>& k, std::size_t j, std::size_t c, double s)
{
    s = std::clamp(s, 0.0, 8.0);
    const auto i = std::min<std::size_t>(static_cast<std::size_t>(s), 7);
    const double f = s - double(i);
    return (1 - f) * k.at(i, j, c) + f * k.at(i + 1, j, c);
}

/// Content `c`'s neutral keyframes: a waveform of its own per channel (another frequency and phase per content).
keyframes<9> content_wave(std::size_t content, std::size_t joints)
{
    auto k = keyframes<9>::make(joints);
    for (std::size_t i = 0; i < 9; ++i)
        for (std::size_t j = 0; j < joints; ++j)
            for (std::size_t c = 0; c < 3; ++c)
                k.at(i, j, c) = 20.0 * std::sin(0.5 * double(content + 2) * double(i) + 0.9 * double(j) + 0.4 * double(c) + double(content)) +
                                5.0 * double(c);
    return k;
}

/// The keyframes `k` with each joint shifted by lag[j] (out of place, curve_at()).
keyframes<9> shifted(const keyframes<9>& k, const std::vector<double>& lag)
{
    auto o = k;
    for (std::size_t i = 0; i < 9; ++i)
        for (std::size_t j = 0; j < k.joints; ++j)
            for (std::size_t c = 0; c < 3; ++c) o.at(i, j, c) = curve_at(k, j, c, double(i) - lag[j]);
    return o;
}

struct lag_set {
    std::vector<labelled_clip> clips;
    std::vector<keyframes<9>> kfs;
    void add(const std::string& content, const std::string& emotion, const std::string& take, keyframes<9> k)
    {
        labelled_clip c;
        c.content = content, c.emotion = emotion, c.take = take;
        clips.push_back(std::move(c));
        kfs.push_back(std::move(k));
    }
};

const std::vector<std::string> domains{"angry", "fearful", "neutral"};

}  // namespace

TEST_CASE("shift_joints: each joint's keyframes read off its curve at k - lag, in place")
{
    const auto k = ramp_keys(3);
    const std::vector<double> lag{1.0, -0.375, 0.0};
    auto s = k;
    stargan::shift_joints(s, lag);
    for (std::size_t i = 0; i < 9; ++i)
        for (std::size_t j = 0; j < 3; ++j)
            for (std::size_t c = 0; c < 3; ++c) {
                CAPTURE(i);
                CAPTURE(j);
                CAPTURE(c);
                CHECK(s.at(i, j, c) == doctest::Approx(curve_at(k, j, c, double(i) - lag[j])).epsilon(1e-15));
            }
    // a whole-keyframe delay moves the values one keyframe later and holds the first; no lag leaves the joint
    CHECK(s.at(0, 0, 0) == k.at(0, 0, 0));
    CHECK(s.at(5, 0, 1) == k.at(4, 0, 1));
    CHECK(s.at(8, 2, 2) == k.at(8, 2, 2));
    // an advance past the end holds the last keyframe
    auto far = k;
    stargan::shift_joints(far, std::vector<double>{-20.0, 0.0, 20.0});
    for (std::size_t i = 0; i < 9; ++i) {
        CHECK(far.at(i, 0, 0) == k.at(8, 0, 0));
        CHECK(far.at(i, 2, 1) == k.at(0, 2, 1));
    }
    // bad lags are refused naming what is wrong
    CHECK_THROWS_WITH_AS(stargan::shift_joints(s, std::vector<double>{1.0}), doctest::Contains("1 lags for 3 joints"), value_error);
    CHECK_THROWS_WITH_AS(stargan::shift_joints(s, std::vector<double>{0.0, std::nan(""), 0.0}), doctest::Contains("joint 1 is not finite"),
                         value_error);
}

TEST_CASE("joint_lags_checked: a planted lag is recovered, kept by the check, and an emotion without one gets none")
{
    const std::size_t J = 4;
    const std::vector<double> planted{0.0, 0.5, 1.0, 1.5};  // a finger lag growing along the joints
    lag_set d;
    for (std::size_t c = 0; c < 4; ++c)
        for (const char* take : {"1", "2"}) {
            const auto n = content_wave(c, J);
            d.add("content" + std::to_string(c), "neutral", take, n);
            d.add("content" + std::to_string(c), "fearful", take, shifted(n, planted));
            auto a = n;  // angry: larger excursions, no lag
            for (auto& v : a.angles) v *= 1.5;
            d.add("content" + std::to_string(c), "angry", take, a);
        }
    const auto r = stargan::joint_lags_checked<9>(d.clips, d.kfs, domains, "neutral", {1.5, 1.0, 1.0});
    REQUIRE(r.lag.size() == 3);
    CHECK(r.kept[1]);
    CHECK(r.lag[1] == planted);
    CHECK(r.check[1].second < 1e-9);   // the left-out contents' fearful takes are met exactly
    CHECK(r.check[1].first > 1.0);     // and were far without the lag
    // angry scaled by its amplitude factor is met without a lag: nothing to keep
    CHECK(!r.kept[0]);
    CHECK(r.lag[0] == std::vector<double>(J, 0.0));
    CHECK(r.check[0].first < 1e-9);
    // neutral has no lag and no check
    CHECK(!r.kept[2]);
    CHECK(std::isnan(r.check[2].first));
}

TEST_CASE("joint_lags_checked: a lag that differs from content to content does not carry over and is not kept")
{
    const std::size_t J = 3;
    lag_set d;
    for (std::size_t c = 0; c < 4; ++c) {
        const auto n = content_wave(c, J);
        const double l = (c % 2 ? 1.0 : -1.0) * (1.0 + 0.25 * double(c));  // each content lags its own way
        d.add("content" + std::to_string(c), "neutral", "1", n);
        d.add("content" + std::to_string(c), "fearful", "1", shifted(n, std::vector<double>(J, l)));
    }
    const auto r = stargan::joint_lags_checked<9>(d.clips, d.kfs, {"fearful", "neutral"}, "neutral", {1.0, 1.0});
    CHECK(!r.kept[0]);
    CHECK(r.check[0].second >= r.check[0].first);
    CHECK(r.lag[0] == std::vector<double>(J, 0.0));
    // one content: no check is possible, so nothing is kept
    lag_set one;
    one.add("c", "neutral", "1", content_wave(0, J));
    one.add("c", "fearful", "1", shifted(content_wave(0, J), std::vector<double>(J, 1.0)));
    const auto r1 = stargan::joint_lags_checked<9>(one.clips, one.kfs, {"fearful", "neutral"}, "neutral", {1.0, 1.0});
    CHECK(!r1.kept[0]);
    CHECK(std::isnan(r1.check[0].first));
    // mismatched sizes are refused
    CHECK_THROWS_AS(stargan::joint_lags_checked<9>(one.clips, one.kfs, {"fearful", "neutral"}, "neutral", {1.0}), value_error);
    CHECK_THROWS_WITH_AS(stargan::joint_lags_checked<9>(one.clips, one.kfs, {"fearful", "calm"}, "neutral", {1.0, 1.0}),
                         doctest::Contains("'neutral' is not among"), value_error);
}
