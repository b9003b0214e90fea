// What a transfer writes as a motion image is what it writes as motion: transfer_result::image holds the output's
// keyframes (Eq. 3), not G's own output; transfer_keyframes() (an input given by its keyframes, such as a motion
// image) takes the steps a clip's keyframes take; and G runs only for a target whose gate keeps some of its change.
#include <doctest/doctest.h>
#include <handemo/motion/codec.hpp>
#include <handemo/motion/synth.hpp>
#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/continuous.hpp>
#include <handemo/stargan/transfer.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

using namespace handemo;
using namespace handemo::stargan;

namespace {

using model_t = stargan::detail::emotion_model_impl<hand_embedded>;

std::pair<safetensors_file, checkpoint_info> shipped()
{
    return read_checkpoint(std::filesystem::path(HANDEMO_SOURCE_DIR) / "data" / "models" / "hand-embedded" / "checkpoint.safetensors");
}

/// Every angle of `a` (an image decoded by Eq. 6) within half a pixel level of `b`'s where `range` holds `b`'s (Eq. 3
/// clamps the others); the count compared.
std::size_t expect_within_half_level(const keyframes<dynamic_keyframes>& a, const keyframes<dynamic_keyframes>& b, const angle_range& range)
{
    REQUIRE(a.angles.size() == b.angles.size());
    const std::size_t C = b.joints * 3;
    std::size_t compared = 0;
    for (std::size_t i = 0; i < b.angles.size(); ++i) {
        const std::size_t ch = i % C;
        if (!range.contains(b.angles[i], ch)) continue;
        ++compared;
        const double span = range.per_channel() ? range.hi[ch] - range.lo[ch] : range.p_max - range.p_min;
        CHECK(std::abs(wrap_angle_deg(a.angles[i] - b.angles[i])) <= span / 255.0 / 2 + 1e-9);
    }
    return compared;
}

/// The gate's weights of `target` in `m`, within the model's joint limits (as its transfers' keyframes).
keyframes<dynamic_keyframes> gated(const emotion_model& m, const transfer_parts& p)
{
    const auto& i = m.info();
    auto k = m.combine(p, i.gate_posture[p.target], i.gate_motion[p.target], i.gate_prior.empty() ? 0.0 : i.gate_prior[p.target]);
    m.clamp_to_limits(k);
    return k;
}

}  // namespace

TEST_CASE("a transfer's motion image holds the keyframes its motion passes through, whatever the gate")
{
    const auto ck = shipped();
    model_t shipped_gate(ck.first, ck.second);
    model_t g_gate(ck.first, ck.second);
    const std::size_t D = ck.second.domains.size();
    // every target with G's posture whole and half its motion, the prior whole: G's change reaches the output
    g_gate.set_gate(std::vector<double>(D, 1.0), std::vector<double>(D, 0.5), std::vector<double>(D, 1.0));
    const clip in = synthesize(hand_motion::pointing, emotion::neutral, 0, 3, 30.0);
    const auto& range = ck.second.range;
    for (const model_t* m : {&shipped_gate, &g_gate})
        for (const std::string t : {"angry", "happy", "sad", "fearful"}) {
            CAPTURE(t);
            const auto r = m->transfer(in, t);
            const auto parts = m->parts(in, t);
            const auto out_keys = gated(*m, parts);
            // the image is the gated output's keyframes (Eq. 3 then Eq. 6 give them back to half a pixel level)
            CHECK(expect_within_half_level(decode(r.image, range), out_keys, range) > out_keys.angles.size() / 2);
            // and the output clip is the spline through those keyframes
            clip again = reconstruct(out_keys, in.skel, r.motion.frames, in.fps);
            m->clamp_to_limits(again);
            CHECK(std::memcmp(again.angles.data(), r.motion.angles.data(), again.angles.size() * sizeof(double)) == 0);
            // G's own image stays in the parts, and differs from the output's
            CHECK(parts.run_generator);
            CHECK(parts.image.values.size() == r.image.values.size());
            CHECK(parts.image.values != r.image.values);
        }
    // statistics() too: its image is its motion's keyframes
    const auto s = shipped_gate.statistics(in, "sad");
    const auto sp = shipped_gate.parts(in, "sad");
    CHECK(expect_within_half_level(decode(s.image, range), shipped_gate.combine(sp, 0, 0, 1), range) > 0);
}

TEST_CASE("transfer_keyframes: an input given by its keyframes takes a clip's steps")
{
    const auto ck = shipped();
    model_t m(ck.first, ck.second);
    const std::size_t D = ck.second.domains.size();
    const clip in = synthesize(hand_motion::gripping, emotion::neutral, 1, 3, 30.0);
    const auto kf = extract_keyframes<dynamic_keyframes>(in, m.keyframes());
    for (const bool with_g : {false, true}) {
        CAPTURE(with_g);
        if (with_g) m.set_gate(std::vector<double>(D, 0.75), std::vector<double>(D, 0.25), std::vector<double>(D, 1.0));
        for (const std::string t : {"angry", "sad", "neutral"}) {
            CAPTURE(t);
            const auto out = m.transfer_keyframes(kf, t);
            const auto expect = gated(m, m.parts(in, t));
            REQUIRE(out.angles.size() == expect.angles.size());
            CHECK(std::memcmp(out.angles.data(), expect.angles.data(), out.angles.size() * sizeof(double)) == 0);
        }
        // from another source emotion: the amplitude and the lag read it as a clip's transfer does
        const auto out = m.transfer_keyframes(kf, "happy", "sad");
        const auto expect = gated(m, m.parts(in, "happy", "sad"));
        CHECK(std::memcmp(out.angles.data(), expect.angles.data(), out.angles.size() * sizeof(double)) == 0);
    }
    // refusals: another shape, a NaN (its keyframe and joint named), an unknown emotion
    auto fewer = kf;
    fewer.count_ = kf.count() - 1;
    fewer.angles.resize(fewer.count_ * kf.joints * 3);
    CHECK_THROWS_WITH_AS(m.transfer_keyframes(fewer, "sad"), doctest::Contains("keyframes are 8x23"), shape_error);
    auto bad = kf;
    bad.angles[2 * kf.joints * 3 + 5 * 3 + 1] = std::numeric_limits<double>::quiet_NaN();
    const std::string where = "keyframe 2, joint '" + ck.second.joint_names[5] + "'";
    CHECK_THROWS_WITH_AS(m.transfer_keyframes(bad, "sad"), doctest::Contains(where.c_str()), value_error);
    CHECK_THROWS_WITH_AS(m.transfer_keyframes(kf, "bored"), doctest::Contains("bored"), value_error);
}

TEST_CASE("G runs only for a target whose gate keeps some of its change")
{
    // A G whose weights are NaN fails every call that runs it; the shipped gates (every emotion's the statistics
    // setting) never run it, so those transfers succeed and equal the sound model's bit for bit.
    auto ck = shipped();
    const model_t sound(ck.first, ck.second);
    std::size_t poisoned = 0;
    for (auto& t : ck.first.tensors)
        if (t.name.rfind("G.", 0) == 0 || t.name.rfind("G_ema.", 0) == 0) {
            if (t.dtype == st_dtype::f32) {
                const float nan = std::numeric_limits<float>::quiet_NaN();
                for (std::size_t i = 0; i < t.numel(); ++i) std::memcpy(t.data.data() + i * sizeof(float), &nan, sizeof(float));
            } else {
                REQUIRE(t.dtype == st_dtype::f16);
                const std::uint16_t nan = 0x7E00;  // a binary16 quiet NaN
                for (std::size_t i = 0; i < t.numel(); ++i) std::memcpy(t.data.data() + i * sizeof(nan), &nan, sizeof(nan));
            }
            ++poisoned;
        }
    REQUIRE(poisoned > 0);
    model_t broken(ck.first, ck.second);
    const std::size_t D = ck.second.domains.size();
    for (std::size_t d = 0; d < D; ++d)  // neutral keeps G's whole change (a neutral input's reconstruction)
        if (ck.second.domains[d] != ck.second.neutral) REQUIRE((ck.second.gate_posture[d] == 0 && ck.second.gate_motion[d] == 0));
    CHECK_THROWS_WITH_AS(broken.transfer(synthesize(hand_motion::patting, emotion::neutral, 0, 3, 30.0), ck.second.neutral),
                         doctest::Contains("non-finite"), value_error);
    const clip in = synthesize(hand_motion::patting, emotion::neutral, 0, 3, 30.0);
    std::vector<clip> folder{in, synthesize(hand_motion::crawling, emotion::neutral, 2, 3, 30.0)};
    std::vector<transfer_result> batch(folder.size());
    auto bws = broken.make_batch_workspace(2);
    for (const std::string t : {"angry", "sad"}) {
        CAPTURE(t);
        const auto a = broken.transfer(in, t), b = sound.transfer(in, t);
        CHECK(std::memcmp(a.motion.angles.data(), b.motion.angles.data(), a.motion.angles.size() * sizeof(double)) == 0);
        CHECK(a.image.values == b.image.values);
        CHECK(broken.transfer_keyframes(extract_keyframes<dynamic_keyframes>(in, broken.keyframes()), t).angles ==
              sound.transfer_keyframes(extract_keyframes<dynamic_keyframes>(in, sound.keyframes()), t).angles);
        broken.transfer_batch(folder, t, {}, bws, batch);
        CHECK(batch[0].motion.angles == b.motion.angles);
        // the old way, G run and weighed 0, gives the same bits on the sound model
        const auto p = sound.parts(in, t);
        const clip old = sound.finish(in, p, 0, 0, 1);
        CHECK(std::memcmp(old.angles.data(), b.motion.angles.data(), old.angles.size() * sizeof(double)) == 0);
    }
    // the continuous control blends the labels' gated transfers: between two labels whose gates keep none of G's
    // change it needs no G either (the point halfway from angry's direction to sad's, about neutral)
    const auto table = load_circumplex(std::filesystem::path(HANDEMO_SOURCE_DIR) / "data" / "rcm" / "circumplex.json");
    const continuous_control sound_dial(sound, table), broken_dial(broken, table);
    const auto& pa = table.at("angry");
    const auto& ps = table.at("sad");
    const double v = 0.5 * (pa.valence + ps.valence), a = 0.5 * (pa.arousal + ps.arousal);
    const auto w = sound_dial.weights(v, a);
    REQUIRE(w[sound.domain(ck.second.neutral)] == 0.0);  // no weight on neutral, whose gate runs G
    CHECK(broken_dial.transfer(in, v, a).motion.angles == sound_dial.transfer(in, v, a).motion.angles);
    CHECK_THROWS_WITH_AS(broken_dial.transfer(in, 0.0, 0.0), doctest::Contains("non-finite"), value_error);  // neutral's point
    // angles outside the model's range reach G clamped: reported where G runs, not where it does not
    clip wide = in;
    const std::size_t J3 = wide.skel.size() * 3;
    for (std::size_t f = 0; f < wide.frames; ++f) wide.angles[f * J3 + 15] += 90.0;
    const auto wide_parts = sound.parts(wide, "sad");
    REQUIRE(wide_parts.clamped_values > 0);
    CHECK(sound.transfer(wide, "sad").clamped_values == 0);
    CHECK(sound.transfer(wide, ck.second.neutral).clamped_values == wide_parts.clamped_values);
    // parts() always runs G (the gate's fit needs its change), and a gate that keeps some of G's change runs it
    CHECK_THROWS_WITH_AS(broken.parts(in, "sad"), doctest::Contains("non-finite"), value_error);
    auto g_gate = std::vector<double>(D, 0.0);
    g_gate[broken.domain("sad")] = 0.25;
    broken.set_gate(std::vector<double>(D, 0.0), g_gate, std::vector<double>(D, 1.0));
    CHECK_NOTHROW(broken.transfer(in, "angry"));
    CHECK_THROWS_WITH_AS(broken.transfer(in, "sad"), doctest::Contains("non-finite"), value_error);
    CHECK_THROWS_WITH_AS(broken.transfer_batch(folder, "sad", {}, bws, batch), doctest::Contains("non-finite"), value_error);
}
