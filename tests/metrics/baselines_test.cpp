#include "helpers.hpp"

#include <doctest/doctest.h>
#include <handemo/metrics/baselines.hpp>

using namespace handemo;
using namespace handemo::metrics;
using handemo::metrics::test::sine_clip;

namespace {

handemo::labelled_clip item(std::string content, std::string emotion, std::string take, clip c)
{
    handemo::labelled_clip l;
    l.path = "x_" + content + "_" + emotion + "_" + take + ".bvh";
    l.content = std::move(content), l.emotion = std::move(emotion), l.take = std::move(take), l.motion = std::move(c);
    return l;
}

/// Two contents (amplitudes 10 and 30), neutral and angry takes; angry = neutral + 10 deg (content a) and
/// + 20 deg (content b) on every channel.
std::vector<handemo::labelled_clip> tiny_set()
{
    std::vector<handemo::labelled_clip> d;
    for (int take = 0; take < 2; ++take) {
        const double jitter = take;  // takes differ a little
        d.push_back(item("a", "neutral", std::to_string(take), sine_clip(61, 30, 10 + jitter)));
        d.push_back(item("a", "angry", std::to_string(take), sine_clip(61, 30, 10 + jitter, 10.0)));
        d.push_back(item("b", "neutral", std::to_string(take), sine_clip(61, 30, 30 + jitter, 0.0, 2.0)));
        d.push_back(item("b", "angry", std::to_string(take), sine_clip(61, 30, 30 + jitter, 20.0, 2.0)));
    }
    return d;
}

}  // namespace

TEST_CASE("identity baseline returns the input")
{
    const clip a = sine_clip(31, 30, 10);
    const clip b = identity_baseline(a);
    CHECK(b.angles == a.angles);
    CHECK(b.frames == a.frames);
}

TEST_CASE("mean offset: the mean paired keyframe difference, added to a new input")
{
    const auto d = tiny_set();
    const auto b = mean_offset_baseline<9>::fit(d, "neutral");
    const auto delta = b.delta("angry", 23);
    for (double v : delta.angles) CHECK(v == doctest::Approx(15.0).epsilon(1e-9));  // (10 + 20) / 2 over 4 pairs
    for (double v : b.delta("neutral", 23).angles) CHECK(v == 0.0);
    CHECK_THROWS_AS(b.delta("sad", 23), value_error);
    // a new motion: output keyframes = input keyframes + 15
    const clip in = sine_clip(41, 30, 17, 0.0, 1.5);
    const clip out = b.transfer(in, "angry");
    CHECK(out.frames == in.frames);
    const auto ki = extract_keyframes<9>(in), ko = extract_keyframes<9>(out);
    for (std::size_t i = 0; i < ki.angles.size(); ++i) CHECK(ko.angles[i] - ki.angles[i] == doctest::Approx(15.0).epsilon(1e-9));
    // tempo scales the duration
    CHECK(b.transfer(in, "angry", 2.0).frames == 82);
    CHECK(b.transfer(in, "angry", 0.5).frames == 21);
    CHECK_THROWS_AS(mean_offset_baseline<9>::fit({d[1], d[3]}, "neutral"), value_error);
}

TEST_CASE("mean offset pairs an emotion take with the content's first neutral take when its own is missing")
{
    auto d = tiny_set();
    // drop the neutral take 1 of content a: angry a/1 pairs with neutral a/0 (offset 10 + a 1-degree amplitude change)
    d.erase(d.begin() + 4);
    REQUIRE(d[4].emotion == "angry");
    const auto b = mean_offset_baseline<9>::fit(d, "neutral");
    const auto delta = b.delta("angry", 23);
    // the mean stays 15 at keyframes where the sine is 0 (the first keyframe, phase k/7 aside, is not): check
    // the mean over channels of the offset part instead: mean over all values equals 15 + mean amplitude term
    double mean = 0;
    for (double v : delta.angles) mean += v / static_cast<double>(delta.angles.size());
    CHECK(mean == doctest::Approx(15.0).epsilon(0.05));
}

TEST_CASE("nearest neighbour picks the closest training clip of the target emotion")
{
    const auto d = tiny_set();
    // close to content b angry take 1 (amplitude 31, offset 20, 2 cycles)
    const clip q = sine_clip(61, 30, 31.2, 20.1, 2.0);
    const std::size_t i = nearest_neighbour<9>(q, d, "angry");
    CHECK(d[i].content == "b");
    CHECK(d[i].take == "1");
    CHECK(d[i].emotion == "angry");
    // a neutral-looking query still gets an angry clip when angry is asked for
    const std::size_t n = nearest_neighbour<9>(sine_clip(61, 30, 10), d, "angry");
    CHECK(d[n].emotion == "angry");
    CHECK(d[n].content == "a");
    CHECK_THROWS_AS(nearest_neighbour<9>(q, d, "sad"), value_error);
}
