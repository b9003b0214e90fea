// transfer() with a workspace and a result to reuse allocates nothing after its first call for a clip length:
// the allocation counter of tests/alloc_hook.hpp (this program's operator new) around repeated transfers of the
// shipped model, which has every stage (amplitude, residual change, gate, posture prior, tempo). The results
// equal the allocating calls' bit for bit; transfer_batch() gives each clip the bits of its transfer(), and
// transfer_capture_batch() each capture the bits of its transfer_capture(), a failing capture failing alone.
#include <doctest/doctest.h>
#include <handemo/motion/synth.hpp>
#include <handemo/stargan/capture.hpp>
#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/transfer.hpp>

#include "../alloc_hook.hpp"
#include "../retarget/rigs.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

using namespace handemo;
using namespace handemo::stargan;

TEST_CASE("transfer with a workspace: no allocation after the first call for a clip length, same bits")
{
    const auto ck = read_checkpoint(std::filesystem::path(HANDEMO_SOURCE_DIR) / "data" / "models" / "hand-embedded" / "checkpoint.safetensors");
    const stargan::detail::emotion_model_impl<hand_embedded> model(ck.first, ck.second);
    REQUIRE(model.amplitude_stage());
    REQUIRE(model.residual());
    const clip a = synthesize(hand_motion::gripping, emotion::neutral, 0, 3, 30.0);
    clip b = a;  // as long as a, other angles
    for (std::size_t i = 0; i < b.angles.size(); ++i) b.angles[i] += 3.0 * std::sin(0.37 * static_cast<double>(i));
    const clip longer = reconstruct(extract_keyframes<9>(a), a.skel, a.frames + 17, a.fps);

    auto ws = model.make_workspace();
    transfer_result out;
    model.transfer(a, "sad", {}, ws, out);  // the first call for this length sizes every buffer
    const std::vector<std::string> targets = {"angry", "happy", "sad", "fearful", "neutral"};
    const long before = handemo_test::alloc_count.load();
    for (int round = 0; round < 3; ++round)
        for (const auto& t : targets) {
            model.transfer(a, t, {}, ws, out);
            model.transfer(b, t, "neutral", ws, out);
        }
    CHECK(handemo_test::alloc_count.load() - before == 0);

    // the same numbers as the allocating call
    for (const auto& t : targets) {
        model.transfer(b, t, {}, ws, out);
        const auto fresh = model.transfer(b, t);
        CHECK(out.motion.frames == fresh.motion.frames);
        CHECK(std::memcmp(out.motion.angles.data(), fresh.motion.angles.data(), out.motion.angles.size() * sizeof(double)) == 0);
        CHECK(std::memcmp(out.motion.positions.data(), fresh.motion.positions.data(), out.motion.positions.size() * sizeof(double)) == 0);
        CHECK(out.image.values == fresh.image.values);
        CHECK(out.tempo == fresh.tempo);
        CHECK(out.clamped_values == fresh.clamped_values);
    }

    // a longer clip grows the buffers once; then no allocation again
    model.transfer(longer, "angry", {}, ws, out);
    const long grown = handemo_test::alloc_count.load();
    model.transfer(longer, "happy", {}, ws, out);
    CHECK(handemo_test::alloc_count.load() - grown == 0);
    // and the shorter clip fits in what is there
    const long again = handemo_test::alloc_count.load();
    model.transfer(a, "sad", {}, ws, out);
    CHECK(handemo_test::alloc_count.load() - again == 0);
}

TEST_CASE("transfer_batch: each clip's result equals its transfer() bit for bit, in batches of any size")
{
    const auto ck = read_checkpoint(std::filesystem::path(HANDEMO_SOURCE_DIR) / "data" / "models" / "hand-embedded" / "checkpoint.safetensors");
    const stargan::detail::emotion_model_impl<hand_embedded> model(ck.first, ck.second);
    std::vector<clip> clips;
    for (int take = 0; take < 7; ++take) {  // different motions, takes and lengths
        const auto motion = take % 2 ? hand_motion::gripping : hand_motion::pointing;
        clip c = synthesize(motion, take % 3 ? emotion::neutral : emotion::happy, take, 5, 30.0);
        if (take == 4) c = reconstruct(extract_keyframes<9>(c), c.skel, c.frames + 23, c.fps);
        clips.push_back(std::move(c));
    }
    for (const std::size_t batch : {std::size_t(3), std::size_t(7), std::size_t(16)}) {
        CAPTURE(batch);
        auto ws = model.make_batch_workspace(batch);
        CHECK(ws.capacity() == batch);
        std::vector<transfer_result> out(clips.size());
        model.transfer_batch(clips, "angry", {}, ws, out);
        for (std::size_t i = 0; i < clips.size(); ++i) {
            CAPTURE(i);
            const auto one = model.transfer(clips[i], "angry");
            REQUIRE(out[i].motion.frames == one.motion.frames);
            CHECK(std::memcmp(out[i].motion.angles.data(), one.motion.angles.data(), one.motion.angles.size() * sizeof(double)) == 0);
            CHECK(std::memcmp(out[i].motion.positions.data(), one.motion.positions.data(), one.motion.positions.size() * sizeof(double)) == 0);
            CHECK(out[i].image.values == one.image.values);
            CHECK(out[i].tempo == one.tempo);
            CHECK(out[i].amplitude == one.amplitude);
        }
    }
    auto ws = model.make_batch_workspace(4);
    std::vector<transfer_result> few(2);
    CHECK_THROWS_WITH_AS(model.transfer_batch(clips, "sad", {}, ws, few), doctest::Contains("7 clips into 2 results"), value_error);
    CHECK_THROWS_AS(model.transfer_batch(clips, "bored", {}, ws, few = std::vector<transfer_result>(7)), value_error);
}

TEST_CASE("transfer_capture_batch: each capture as transfer_capture() gives it, through retargeting; a failing capture fails alone")
{
    const auto ck = read_checkpoint(std::filesystem::path(HANDEMO_SOURCE_DIR) / "data" / "models" / "hand-embedded" / "checkpoint.safetensors");
    const stargan::detail::emotion_model_impl<hand_embedded> model(ck.first, ck.second);
    std::vector<clip> in;
    in.push_back(synthesize(hand_motion::pointing, emotion::neutral, 0, 9, 30.0));  // on the model's skeleton
    in.push_back(test::random_motion(test::make_rig(test::openxr_names('r', false), {}), 90, 4, 15));  // retargeted
    in.push_back(test::random_motion(test::make_rig(test::cmu_names(), {}), 40, 2, 10));  // a body without fingers: refused
    in.push_back(synthesize(hand_motion::gripping, emotion::happy, 1, 9, 30.0));
    std::vector<capture_options> options(in.size());
    options[3].detail = model.has_detail();
    auto ws = model.make_batch_workspace(2);
    std::vector<capture_result> out(in.size());
    const auto errors = transfer_capture_batch(model, in, "fearful", {}, options, ws, out);
    REQUIRE(errors.size() == in.size());
    for (std::size_t i = 0; i < in.size(); ++i) {
        CAPTURE(i);
        if (i == 2) {
            CHECK_FALSE(errors[i].empty());
            std::string direct;
            try {
                transfer_capture(model, in[i], "fearful", {}, options[i]);
            } catch (const std::exception& e) {
                direct = e.what();
            }
            CHECK(errors[i] == direct);
            continue;
        }
        REQUIRE(errors[i].empty());
        const auto one = transfer_capture(model, in[i], "fearful", {}, options[i]);
        CHECK(out[i].retargeted == one.retargeted);
        REQUIRE(out[i].motion.frames == one.motion.frames);
        CHECK(out[i].motion.angles == one.motion.angles);  // bit for bit
        CHECK(out[i].motion.positions == one.motion.positions);
        CHECK(out[i].on_model.image.values == one.on_model.image.values);
    }
    CHECK(out[1].retargeted);
    CHECK_THROWS_AS(transfer_capture_batch(model, in, "bored", {}, options, ws, out), value_error);
}
