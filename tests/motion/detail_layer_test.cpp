#include <handemo/motion/detail_layer.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/motion/synth.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

using namespace handemo;

namespace {
constexpr double two_pi = 2 * std::numbers::pi;

// A smooth base motion plus, on channels 3k (k < 6), a sinusoid of `hz` and amplitude `amp` with a zero at every
// keyframe when `hz` is a multiple of 4 at 241 frames and 120 fps (keyframes every 0.25 s).
clip detailed_clip(double hz, double amp, std::size_t frames = 241, double fps = 120.0, double base = 15.0)
{
    clip c = clip::make(hand_skeleton(), frames, fps);
    const std::size_t C = c.skel.size() * 3;
    for (std::size_t f = 0; f < frames; ++f) {
        const double t = static_cast<double>(f) / fps;
        for (std::size_t ch = 0; ch < C; ++ch) {
            double v = base * std::sin(two_pi * 0.3 * t + 0.2 * static_cast<double>(ch));
            if (ch % 3 == 0 && ch < 18) v += amp * std::sin(two_pi * hz * t);
            c.angles[f * C + ch] = v;
        }
    }
    return c;
}

double max_keyframe_change(const clip& a, const clip& b)
{
    const auto ka = extract_keyframes<9>(a), kb = extract_keyframes<9>(b);
    double m = 0;
    for (std::size_t i = 0; i < ka.angles.size(); ++i) m = std::max(m, std::abs(ka.angles[i] - kb.angles[i]));
    return m;
}
}  // namespace

TEST_CASE("detail_residual: a keyframe spline has no detail; a sinusoid between keyframes is all detail")
{
    // reconstruct() of keyframes is its own spline
    auto kf = keyframes<9>::make(23);
    for (std::size_t i = 0; i < kf.angles.size(); ++i) kf.angles[i] = 30.0 * std::sin(0.37 * static_cast<double>(i));
    const clip s = reconstruct(kf, hand_skeleton(), 161, 60.0);
    for (double r : detail_residual<9>(s)) REQUIRE(std::abs(r) < 1e-9);

    // 8 Hz with zeros at the keyframes: the residual is the sinusoid (to the base's own spline error)
    const clip c = detailed_clip(8.0, 2.0);
    const clip base = detailed_clip(8.0, 0.0);
    const auto r = detail_residual<9>(c), rb = detail_residual<9>(base);
    const std::size_t C = 69;
    for (std::size_t f = 0; f < c.frames; ++f) {
        CHECK(r[f * C + 0] - rb[f * C + 0] == doctest::Approx(2.0 * std::sin(two_pi * 8.0 * static_cast<double>(f) / 120.0)).epsilon(1e-9).scale(1));
        CHECK(std::abs(r[f * C + 1] - rb[f * C + 1]) < 1e-12);  // no sinusoid on channel 1
    }
    CHECK(std::abs(r[0]) < 1e-12);  // the first and last frames are keyframes
    CHECK(std::abs(r[(c.frames - 1) * C]) < 1e-12);
}

TEST_CASE("measure_detail: RMS amplitude and RMS frequency of a sinusoid")
{
    const auto s = measure_detail<9>(detailed_clip(8.0, 2.0)), s0 = measure_detail<9>(detailed_clip(8.0, 0.0));
    // amplitude of a sinusoid: amp / sqrt 2 (241 frames hold 16 whole cycles plus one sample)
    CHECK(s.amplitude[0] == doctest::Approx(2.0 / std::sqrt(2.0)).epsilon(0.02));
    CHECK(s.amplitude[1] == doctest::Approx(s0.amplitude[1]).epsilon(1e-9));
    // velocity RMS = 2 pi f amp / sqrt 2, times the backward difference's sinc factor sin(pi f / fps) / (pi f / fps)
    const double x = std::numbers::pi * 8.0 / 120.0;
    CHECK(s.velocity[0] == doctest::Approx(two_pi * 8.0 * 2.0 / std::sqrt(2.0) * std::sin(x) / x).epsilon(0.02));
    // the pooled frequency of the sinusoid channels alone is 8 Hz (the base's spline error is tiny beside it)
    detail_stats only;
    for (std::size_t ch = 0; ch < 18; ch += 3) only.amplitude.push_back(s.amplitude[ch]), only.velocity.push_back(s.velocity[ch]);
    CHECK(only.frequency() == doctest::Approx(8.0).epsilon(0.02));
    CHECK(detail_stats{}.frequency() == 0.0);
}

TEST_CASE("detail_layer: fit learns per-emotion amplitude and frequency, apply moves the output's detail there")
{
    const clip calm = detailed_clip(4.0, 1.0), calm2 = detailed_clip(4.0, 1.2);
    const clip shaky = detailed_clip(16.0, 3.0), shaky2 = detailed_clip(16.0, 3.6);
    const auto layer = detail_layer::fit({{&calm, "calm"}, {&shaky, "shaky"}, {&calm2, "calm"}, {&shaky2, "shaky"}});
    REQUIRE(layer.emotions == std::vector<std::string>{"calm", "shaky"});
    CHECK(layer.clips == std::vector<std::size_t>{2, 2});
    CHECK(layer.amplitude[0][0] == doctest::Approx(1.1 / std::sqrt(2.0)).epsilon(0.03));
    CHECK(layer.amplitude[1][0] == doctest::Approx(3.3 / std::sqrt(2.0)).epsilon(0.03));
    CHECK(layer.gain("calm", "shaky", 0) == doctest::Approx(3.0).epsilon(0.03));
    CHECK(layer.gain("shaky", "calm", 0) == doctest::Approx(1.0 / 3.0).epsilon(0.03));
    CHECK(layer.frequency[1] / layer.frequency[0] > 3.0);  // pooled over all channels: the base pulls both down
    CHECK(layer.rate("calm", "calm") == 1.0);

    // The transfer calm -> shaky of a calm input whose output is its own keyframe spline (no detail).
    const clip input = detailed_clip(4.0, 1.0);
    const clip spline = reconstruct(extract_keyframes<9>(input), input.skel, input.frames, input.fps);
    const clip out = layer.apply(spline, input, "calm", "shaky");
    // the keyframes do not move (they are exact frames here)
    CHECK(max_keyframe_change(out, spline) < 1e-9);
    // the added detail is the input's, `gain` times larger, `rate` times faster
    const auto si = measure_detail<9>(input), so = measure_detail<9>(out);
    // (give or take the bumps that zero it at the keyframes, half a period wide at each of 9 keyframes)
    CHECK(so.amplitude[0] == doctest::Approx(layer.gain("calm", "shaky", 0) * si.amplitude[0]).epsilon(0.10));
    detail_stats in_f, out_f;
    for (std::size_t ch = 0; ch < 18; ch += 3) {
        in_f.amplitude.push_back(si.amplitude[ch]), in_f.velocity.push_back(si.velocity[ch]);
        out_f.amplitude.push_back(so.amplitude[ch]), out_f.velocity.push_back(so.velocity[ch]);
    }
    CHECK(out_f.frequency() == doctest::Approx(layer.rate("calm", "shaky") * in_f.frequency()).epsilon(0.10));
    // same emotion: the input's own detail comes back on its own spline
    const clip back = layer.apply(spline, input, "calm", "calm");
    for (std::size_t i = 0; i < back.angles.size(); ++i) REQUIRE(back.angles[i] == doctest::Approx(input.angles[i]).epsilon(1e-9).scale(1));

    // an output of another length (tempo), keyframes between frames: they do not move either
    for (std::size_t n : {300, 97, 40}) {
        const clip longer = reconstruct(extract_keyframes<9>(input), input.skel, n, input.fps);
        const clip out2 = layer.apply(longer, input, "calm", "shaky");
        CHECK(out2.frames == n);
        CHECK(max_keyframe_change(out2, longer) < 1e-9);
        CHECK(measure_detail<9>(out2).amplitude[0] > 0.5 * layer.gain("calm", "shaky", 0) * si.amplitude[0]);
    }
}

TEST_CASE("detail_layer: frequencies and rates with known answers, the rate bounded and raised to the strength")
{
    // Sinusoids alone (no base motion): a multiple of 4 Hz is zero at every keyframe, so the detail is the sinusoid
    // and each emotion's frequency is its own, times the backward difference's sinc factor sin(x) / x, x = pi f / fps.
    const auto measured = [](double hz) {
        const double x = std::numbers::pi * hz / 120.0;
        return hz * std::sin(x) / x;
    };
    const clip c4 = detailed_clip(4.0, 1.0, 241, 120.0, 0.0), c12 = detailed_clip(12.0, 2.0, 241, 120.0, 0.0);
    const clip c20 = detailed_clip(20.0, 1.5, 241, 120.0, 0.0), still = detailed_clip(4.0, 0.0, 241, 120.0, 0.0);
    auto layer = detail_layer::fit({{&c4, "calm"}, {&c12, "lively"}, {&c20, "frantic"}, {&still, "still"}});
    REQUIRE(layer.emotions == std::vector<std::string>{"calm", "lively", "frantic", "still"});
    CHECK(layer.frequency[0] == doctest::Approx(measured(4.0)).epsilon(0.01));
    CHECK(layer.frequency[1] == doctest::Approx(measured(12.0)).epsilon(0.01));
    CHECK(layer.frequency[2] == doctest::Approx(measured(20.0)).epsilon(0.01));
    CHECK(layer.frequency[3] == 0.0);
    // F[t] / F[s]
    const double r = measured(12.0) / measured(4.0);  // about 2.96
    CHECK(layer.rate("calm", "lively") == doctest::Approx(r).epsilon(0.01));
    CHECK(layer.rate("lively", "calm") == doctest::Approx(1 / r).epsilon(0.01));
    // bounded to [1/4, 4]: 20 Hz against 4 Hz is about 4.9
    CHECK(layer.rate("calm", "frantic") == 4.0);
    CHECK(layer.rate("frantic", "calm") == 0.25);
    CHECK(layer.rate("lively", "frantic") == doctest::Approx(measured(20.0) / measured(12.0)).epsilon(0.01));
    // an emotion without detail plays the input's detail at its own rate
    CHECK(layer.rate("still", "lively") == 1.0);
    CHECK(layer.rate("calm", "still") == 1.0);
    // the strength is the exponent
    layer.strength = 0.5;
    CHECK(layer.rate("calm", "lively") == doctest::Approx(std::sqrt(r)).epsilon(0.01));
    CHECK(layer.rate("calm", "frantic") == 2.0);
    layer.strength = 0.0;
    CHECK(layer.rate("calm", "frantic") == 1.0);
    // a channel past the layer's is a value_error naming it (not std::out_of_range), as is an unknown emotion
    CHECK_THROWS_WITH_AS(layer.gain("calm", "lively", 69), doctest::Contains("channel 69 out of range (69 channels)"), value_error);
    CHECK_THROWS_WITH_AS(layer.rate("calm", "bored"), doctest::Contains("'bored'"), value_error);
}

TEST_CASE("detail_layer::fit_checked: where the statistics hold on every content, it keeps them (strength 1)")
{
    std::vector<clip> clips;
    std::vector<detail_layer::sample> data;
    const char* contents[] = {"a", "b", "c"};
    for (int c = 0; c < 3; ++c) clips.push_back(detailed_clip(4.0, 1.0 + 0.1 * c)), clips.push_back(detailed_clip(16.0, 3.0 + 0.3 * c));
    for (int c = 0; c < 3; ++c) {
        data.push_back({&clips[2 * c], "calm", contents[c], "0"});
        data.push_back({&clips[2 * c + 1], "shaky", contents[c], "0"});
    }
    const auto m = detail_layer::fit_checked(data, "calm");
    REQUIRE(m.check_error.size() == detail_layer::strength_candidates.size());
    CHECK(m.strength == 1.0);
    CHECK(m.check_error.back() < 0.5 * m.check_error.front());
    for (double e : m.check_error) CHECK(std::isfinite(e));
    // the statistics are fit()'s
    const auto plain = detail_layer::fit({{&clips[0], "calm"}, {&clips[1], "shaky"}, {&clips[2], "calm"}, {&clips[3], "shaky"}, {&clips[4], "calm"},
                                          {&clips[5], "shaky"}});
    CHECK(m.amplitude == plain.amplitude);
    // strength 0: the input's detail as it is (gain and rate 1)
    detail_layer z = m;
    z.strength = 0;
    CHECK(z.rate("calm", "shaky") == 1.0);
    CHECK(z.gain("calm", "shaky", 0) == 1.0);
    const auto back = detail_layer::from_json(m.to_json(), "x");
    CHECK(back.strength == m.strength);
    CHECK(back.check_error == m.check_error);
    // a motionless real clip has no ratio: its pairs are left out, the check stays finite
    clip still = clip::make(hand_skeleton(), 241, 120.0);
    auto with_still = data;
    with_still.push_back({&still, "shaky", "c", "1"}), with_still.push_back({&clips[4], "calm", "c", "1"});
    const auto ms = detail_layer::fit_checked(with_still, "calm");
    for (double e : ms.check_error) CHECK(std::isfinite(e));
    CHECK_NOTHROW(detail_layer::from_json(nlohmann::json::parse(ms.to_json().dump()), "x"));
    // one content: nothing to check on, strength 1 and no check
    const auto one = detail_layer::fit_checked({data[0], data[1]}, "calm");
    CHECK(one.strength == 1.0);
    CHECK(one.check_error.empty());
}

TEST_CASE("detail_layer: the synthetic set's fearful tremor shows as more, faster detail than neutral")
{
    std::vector<clip> clips;
    std::vector<std::pair<const clip*, std::string>> data;
    for (auto m : {hand_motion::gripping, hand_motion::pointing})
        for (int take = 0; take < 2; ++take)
            for (auto e : {emotion::neutral, emotion::fearful}) clips.push_back(synthesize(m, e, take, 1, 60.0));
    for (std::size_t i = 0; i < clips.size(); ++i) data.push_back({&clips[i], i % 2 ? "fearful" : "neutral"});
    const auto layer = detail_layer::fit(data);
    CHECK(layer.frequency[layer.index("fearful")] > 1.5 * layer.frequency[layer.index("neutral")]);
}

TEST_CASE("detail_layer: JSON round trip and errors that name the field")
{
    const clip a = detailed_clip(4.0, 1.0), b = detailed_clip(16.0, 3.0);
    const auto layer = detail_layer::fit({{&a, "calm"}, {&b, "shaky"}});
    const auto back = detail_layer::from_json(nlohmann::json::parse(layer.to_json().dump()), "x.json");
    CHECK(back.emotions == layer.emotions);
    CHECK(back.amplitude == layer.amplitude);
    CHECK(back.frequency == layer.frequency);
    CHECK(back.keyframes == 9);

    auto bad = layer.to_json();
    bad["format"] = "handemo-detail/9";
    CHECK_THROWS_WITH_AS(detail_layer::from_json(bad, "x.json"), doctest::Contains("x.json: detail layer: format"), format_error);
    bad = layer.to_json();
    bad["amplitude"][1][4] = -1.0;
    CHECK_THROWS_WITH_AS(detail_layer::from_json(bad, "x.json"), doctest::Contains("amplitude of 'shaky'"), format_error);
    bad = layer.to_json();
    bad["frequency"][0] = std::nan("");
    CHECK_THROWS_AS(detail_layer::from_json(bad, "x.json"), format_error);
    bad = layer.to_json();
    bad.erase("channels");
    CHECK_THROWS_WITH_AS(detail_layer::from_json(bad, "x.json"), doctest::Contains("malformed"), format_error);
    bad = layer.to_json();
    bad["keyframes"] = 1e300;
    CHECK_THROWS_WITH_AS(detail_layer::from_json(bad, "x.json"), doctest::Contains("field 'keyframes'"), format_error);
    bad = layer.to_json();
    bad["strength"] = 1.5;
    CHECK_THROWS_WITH_AS(detail_layer::from_json(bad, "x.json"), doctest::Contains("field 'strength'"), format_error);
    bad = layer.to_json();
    bad["clips"][0] = 1e300;
    CHECK_THROWS_WITH_AS(detail_layer::from_json(bad, "x.json"), doctest::Contains("field 'clips'"), format_error);
    bad = layer.to_json();
    bad["amplitude"][0].erase(0);
    CHECK_THROWS_WITH_AS(detail_layer::from_json(bad, "x.json"), doctest::Contains("channels"), format_error);
    CHECK_THROWS_AS(detail_layer::from_json(nlohmann::json::array(), "x.json"), format_error);

    CHECK_THROWS_WITH_AS(layer.rate("calm", "angry"), doctest::Contains("'angry'"), value_error);
    clip other = clip::make(skeleton{}, 10, 30.0);
    CHECK_THROWS_AS(layer.apply(a, other, "calm", "shaky"), shape_error);
    CHECK_THROWS_AS(detail_layer::fit({}), value_error);
}
