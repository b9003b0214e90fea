// No output of a model leaves the joint limits of its skeleton: the transfer, statistics(), finish() with any
// gate, transfer_keyframes(), the detail layer and the continuous control clamp their keyframes and their
// full-rate frames; a model trained on a hand read from BVH (which carries no limits) keeps the hand's.
#include <doctest/doctest.h>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/motion/synth.hpp>
#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/continuous.hpp>
#include <handemo/stargan/transfer.hpp>
#include <handemo/stargan.hpp>

#include "helpers.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

using namespace handemo;
using namespace handemo::stargan;
namespace fs = std::filesystem;

namespace {

using limits_model = stargan::detail::emotion_model_impl<hand_embedded>;

std::pair<safetensors_file, checkpoint_info> shipped_checkpoint()
{
    return read_checkpoint(std::filesystem::path(HANDEMO_SOURCE_DIR) / "data" / "models" / "hand-embedded" / "checkpoint.safetensors");
}

/// How many rotation angles of `c` (frames x channels) lie outside [lo, hi] per channel.
std::size_t outside_limits(const double* v, std::size_t rows, const std::vector<double>& lo, const std::vector<double>& hi)
{
    std::size_t n = 0;
    for (std::size_t r = 0; r < rows; ++r)
        for (std::size_t c = 0; c < lo.size(); ++c) n += v[r * lo.size() + c] < lo[c] || v[r * lo.size() + c] > hi[c];
    return n;
}

std::size_t outside_limits(const clip& c, const emotion_model& m) { return outside_limits(c.angles.data(), c.frames, m.lower_limits(), m.upper_limits()); }
std::size_t outside_limits(const keyframes<dynamic_keyframes>& k, const emotion_model& m)
{
    return outside_limits(k.angles.data(), k.count(), m.lower_limits(), m.upper_limits());
}

}  // namespace

TEST_CASE("transfers keep the joint limits of the model's skeleton: a model trained on a BVH hand keeps the hand's")
{
    const auto ck = shipped_checkpoint();
    // the shipped model was trained on BVH files: its stored skeleton has no limits of its own
    REQUIRE(ck.second.skel);
    for (const auto& j : ck.second.skel->joints) REQUIRE(j.upper_limit == vec3{180, 180, 180});
    limits_model m(ck.first, ck.second);
    const skeleton hand = hand_skeleton();
    REQUIRE(m.lower_limits().size() == hand.size() * 3);
    for (std::size_t j = 0; j < hand.size(); ++j)
        for (std::size_t a = 0; a < 3; ++a) {
            CHECK(m.lower_limits()[j * 3 + a] == hand.joints[j].lower_limit[a]);
            CHECK(m.upper_limits()[j * 3 + a] == hand.joints[j].upper_limit[a]);
        }

    // a wide grip read back from BVH: angry's amplitude stage would open the fingers past their hyperextension limit
    const clip in = parse_bvh(to_bvh_string(synthesize(hand_motion::gripping, emotion::neutral, 0, 2, 60.0)), "grip.bvh");
    const auto parts = m.parts(in, "angry");
    const auto unclamped = m.combine(parts, 0, 0, 1);
    const std::size_t past = outside_limits(unclamped, m);
    MESSAGE("angry keyframe angles past a limit without the clamp: " << past);
    REQUIRE(past > 0);

    const auto r = m.transfer(in, "angry");
    CHECK(r.limited_values == past);
    CHECK(outside_limits(r.motion, m) == 0);
    CHECK(r.motion.skel.joints[4].upper_limit == vec3{180, 180, 180});  // written on the input's own skeleton
    // the clamp holds each angle at its limit and leaves the others as they were
    auto held = unclamped;
    CHECK(m.clamp_to_limits(held) == past);
    CHECK(m.clamp_to_limits(held) == 0);
    for (std::size_t i = 0; i < held.angles.size(); ++i) {
        const std::size_t ch = i % m.lower_limits().size();
        if (held.angles[i] != unclamped.angles[i])
            CHECK((held.angles[i] == m.lower_limits()[ch] || held.angles[i] == m.upper_limits()[ch]));
    }
    // every other path keeps them too
    CHECK(outside_limits(m.statistics(in, "angry").motion, m) == 0);
    CHECK(m.statistics(in, "angry").limited_values == past);
    for (const double w : {0.0, 0.5, 1.0}) CHECK(outside_limits(m.finish(in, parts, w, w, 1.0), m) == 0);
    CHECK(outside_limits(m.transfer_keyframes(extract_keyframes<dynamic_keyframes>(in, m.keyframes()), "angry"), m) == 0);
    if (m.has_detail()) CHECK(outside_limits(m.add_detail(r.motion, in, "angry"), m) == 0);
    std::vector<transfer_result> batch(2);
    const std::vector<clip> ins{in, in};
    auto bws = m.make_batch_workspace(2);
    m.transfer_batch(ins, "angry", {}, bws, batch);
    CHECK(outside_limits(batch[0].motion, m) == 0);
    CHECK(std::memcmp(batch[0].motion.angles.data(), r.motion.angles.data(), r.motion.angles.size() * sizeof(double)) == 0);

    // the continuous control: at angry's point the discrete transfer bit for bit; along a curve within the limits
    const continuous_control control(m, load_circumplex(std::string(HANDEMO_SOURCE_DIR) + "/data/rcm/circumplex.json"));
    const label_point p = load_circumplex(std::string(HANDEMO_SOURCE_DIR) + "/data/rcm/circumplex.json").at("angry");
    const auto c = control.transfer(in, p.valence, p.arousal);
    CHECK(c.limited_values == past);
    REQUIRE(c.motion.angles.size() == r.motion.angles.size());
    CHECK(std::memcmp(c.motion.angles.data(), r.motion.angles.data(), r.motion.angles.size() * sizeof(double)) == 0);
    va_curve curve;
    curve.time = {0.0, in.duration()};
    curve.valence = {0.0, p.valence};
    curve.arousal = {0.0, p.arousal};
    const auto moving = control.transfer(in, curve);
    CHECK(outside_limits(moving.motion, m) == 0);
    CHECK(outside_limits(moving.keys, m) == 0);
}

TEST_CASE("a model's limits: a skeleton's own limits are kept, a channel spanning the whole circle is not limited")
{
    auto ck = shipped_checkpoint();
    REQUIRE(ck.second.skel);
    ck.second.skel->joints[4].lower_limit = {-10, -180, -180};
    ck.second.skel->joints[4].upper_limit = {40, 180, 180};
    const limits_model m(ck.first, ck.second);  // a hand with a limit of its own: not the hand's limits
    const double inf = std::numeric_limits<double>::infinity();
    for (std::size_t ch = 0; ch < m.lower_limits().size(); ++ch) {
        CAPTURE(ch);
        if (ch == 12) {
            CHECK(m.lower_limits()[ch] == -10);
            CHECK(m.upper_limits()[ch] == 40);
        } else {
            CHECK(m.lower_limits()[ch] == -inf);
            CHECK(m.upper_limits()[ch] == inf);
        }
    }
    // an angle past 180 on an unlimited channel (an unwrapped keyframe) is left as it is
    auto k = extract_keyframes<dynamic_keyframes>(synthesize(hand_motion::pointing, emotion::neutral, 0, 1, 30.0), m.keyframes());
    k.angles[13] = 200, k.angles[12] = 55;
    CHECK(m.clamp_to_limits(k) >= 1);
    CHECK(k.angles[13] == 200);
    CHECK(k.angles[12] == 40);
    // keyframes or a clip of another skeleton are refused, not read past their end
    auto fewer = k;
    fewer.joints = 22, fewer.angles.resize(fewer.count() * 22 * 3);
    CHECK_THROWS_WITH_AS(m.clamp_to_limits(fewer), doctest::Contains("has 22 joints"), shape_error);
    clip body = clip::make(skeleton{"body", {joint{"hips"}}}, 4, 30);
    CHECK_THROWS_WITH_AS(m.clamp_to_limits(body), doctest::Contains("clip body has 1 joints"), shape_error);
}

TEST_CASE("set_limits: a rig's own limits or none; refusals name the joint and axis and leave the model as it was")
{
    const auto ck = shipped_checkpoint();
    limits_model m(ck.first, ck.second);
    const clip in = parse_bvh(to_bvh_string(synthesize(hand_motion::gripping, emotion::neutral, 0, 2, 60.0)), "grip.bvh");
    const std::size_t C = m.joints() * 3;
    const double inf = std::numeric_limits<double>::infinity();
    const auto hand_lower = m.lower_limits(), hand_upper = m.upper_limits();
    CHECK_THROWS_WITH_AS(m.set_limits(std::vector<double>(C - 1, 0.0), std::vector<double>(C, 0.0)), doctest::Contains("69 values each"), value_error);
    auto lo = std::vector<double>(C, -inf), hi = std::vector<double>(C, inf);
    lo[4 * 3 + 1] = 10, hi[4 * 3 + 1] = 5;
    const std::string where = "joint '" + ck.second.joint_names[4] + "' axis y";
    CHECK_THROWS_WITH_AS(m.set_limits(lo, hi), doctest::Contains(where.c_str()), value_error);
    lo[4 * 3 + 1] = std::nan("");
    CHECK_THROWS_AS(m.set_limits(lo, hi), value_error);
    CHECK(m.lower_limits() == hand_lower);
    // none: the output is the spline through the unclamped keyframes
    m.set_limits(std::vector<double>(C, -inf), std::vector<double>(C, inf));
    const auto r = m.transfer(in, "angry");
    CHECK(r.limited_values == 0);
    const clip expect = reconstruct(m.combine(m.parts(in, "angry"), 0, 0, 1), in.skel, r.motion.frames, in.fps);
    CHECK(std::memcmp(expect.angles.data(), r.motion.angles.data(), expect.angles.size() * sizeof(double)) == 0);
    CHECK(outside_limits(r.motion.angles.data(), r.motion.frames, hand_lower, hand_upper) > 0);
}

TEST_CASE("a checkpoint keeps the limits of the skeleton it was trained on, which its BVH text cannot hold")
{
    // a hand built in code with a rig's own limits (the index knuckle's flexion 0..60; the rest unlimited)
    auto clips = toy_set();
    for (auto& c : clips) {
        for (auto& j : c.motion.skel.joints) j.lower_limit = {-360, -360, -360}, j.upper_limit = {360, 360, 360};
        c.motion.skel.joints[8].lower_limit[0] = 0, c.motion.skel.joints[8].upper_limit[0] = 60;
    }
    const fs::path d = fresh_dir("handemo_limits_checkpoint");
    {
        trainer<hand_tiny> t(tiny_info(), prepare_data<hand_tiny>(clips, tiny_info(), quiet(2)), quiet(2));
        t.run(d);
    }
    const auto info = read_checkpoint(d / "checkpoint.safetensors").second;
    REQUIRE(info.skel);
    CHECK(info.skel->joints[8].upper_limit == vec3{60, 360, 360});
    const auto model = load_model(d);
    const double inf = std::numeric_limits<double>::infinity();
    for (std::size_t ch = 0; ch < model->lower_limits().size(); ++ch) {
        CAPTURE(ch);
        CHECK(model->lower_limits()[ch] == (ch == 24 ? 0.0 : -inf));
        CHECK(model->upper_limits()[ch] == (ch == 24 ? 60.0 : inf));
    }
    const auto r = model->transfer(clips[1].motion, "angry");
    for (std::size_t f = 0; f < r.motion.frames; ++f) CHECK((r.motion.angle(f, 8, 0) >= 0 && r.motion.angle(f, 8, 0) <= 60));

    // a skeleton read from BVH writes no field (its checkpoints keep their bytes) and its model takes the hand's limits
    for (auto& c : clips) c.motion.skel = parse_bvh(to_bvh_string(c.motion), "toy.bvh").skel;
    const fs::path b = fresh_dir("handemo_limits_checkpoint_bvh");
    {
        trainer<hand_tiny> t(tiny_info(), prepare_data<hand_tiny>(clips, tiny_info(), quiet(2)), quiet(2));
        t.run(b);
    }
    CHECK_FALSE(nlohmann::json::parse(read_safetensors(b / "checkpoint.safetensors").metadata.at("handemo")).contains("joint_limits"));
    CHECK(load_model(b)->lower_limits()[24] == hand_skeleton().joints[8].lower_limit[0]);

    // a malformed field is refused naming it, and the joint and axis
    auto f = read_safetensors(d / "checkpoint.safetensors");
    const fs::path bad = fresh_dir("handemo_limits_checkpoint_bad");
    fs::create_directories(bad);
    const auto refused = [&](const std::function<void(nlohmann::json&)>& edit, const char* message) {
        auto meta = nlohmann::json::parse(read_safetensors(d / "checkpoint.safetensors").metadata.at("handemo"));
        edit(meta);
        f.metadata["handemo"] = meta.dump();
        f.metadata["checksum"] = handemo::stargan::detail::checkpoint_checksum(f);
        write_safetensors(bad / "checkpoint.safetensors", f);
        CHECK_THROWS_WITH_AS(read_checkpoint(bad / "checkpoint.safetensors"), doctest::Contains(message), format_error);
    };
    refused([](nlohmann::json& m) { m["joint_limits"]["lower"].erase(0); }, "'joint_limits' has 68 lower and 69 upper");
    refused([](nlohmann::json& m) { m["joint_limits"]["upper"][24] = -5.0; }, "joint 'index_proximal' axis x has limits 0.000000..-5.000000");
    refused([](nlohmann::json& m) { m["joint_limits"]["upper"][25] = "wide"; }, "metadata 'handemo' is malformed");
}
