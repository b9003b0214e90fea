// One loaded model shared by 8 threads: every thread transfers the same 12 (input, target) pairs at once, with a workspace of
// its own or a fresh one per call, and must get exactly the single-threaded results (built with
// ThreadSanitizer: CTest label tsan). Also: set_gate() refused leaves the model as it was (strong guarantee), and
// a workspace of another model is refused.
#include <doctest/doctest.h>
#include <handemo/motion/synth.hpp>
#include <handemo/stargan/configs.hpp>
#include <handemo/stargan/transfer.hpp>

#include <cstring>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

using namespace handemo;
using namespace handemo::stargan;

namespace {

std::unique_ptr<emotion_model> shipped()
{
    const auto ck = read_checkpoint(std::filesystem::path(HANDEMO_SOURCE_DIR) / "data" / "models" / "hand-embedded" / "checkpoint.safetensors");
    REQUIRE(ck.second.config == "hand-embedded");
    return std::make_unique<stargan::detail::emotion_model_impl<hand_embedded>>(ck.first, ck.second);
}

bool same_bits(const clip& a, const clip& b)
{
    return a.frames == b.frames && a.angles.size() == b.angles.size() &&
           std::memcmp(a.angles.data(), b.angles.data(), a.angles.size() * sizeof(double)) == 0 &&
           std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(double)) == 0;
}

}  // namespace

TEST_CASE("one model, 8 threads: every transfer equals the single-threaded one, bit for bit")
{
    const auto model = shipped();
    const std::vector<std::string> targets = {"angry", "happy", "sad", "fearful"};
    std::vector<clip> inputs;
    for (auto m : {hand_motion::gripping, hand_motion::pointing, hand_motion::patting}) inputs.push_back(synthesize(m, emotion::neutral, 0, 3, 30.0));
    std::vector<clip> expected;
    for (const auto& in : inputs)
        for (const auto& t : targets) expected.push_back(model->transfer(in, t).motion);
    constexpr int threads = 8, rounds = 1;
    std::vector<int> mismatches(threads, 0), calls(threads, 0);
    std::vector<std::thread> pool;
    for (int k = 0; k < threads; ++k)
        pool.emplace_back([&, k] {
            auto ws = model->make_workspace();
            transfer_result reused;
            for (int r = 0; r < rounds; ++r)
                for (std::size_t i = 0; i < inputs.size(); ++i)
                    for (std::size_t t = 0; t < targets.size(); ++t) {
                        // odd threads use their own workspace and result (the allocation-free call), even threads
                        // a fresh workspace per call
                        if (k % 2) model->transfer(inputs[i], targets[t], {}, ws, reused);
                        const auto out = (k % 2) ? reused : model->transfer(inputs[i], targets[t]);
                        mismatches[static_cast<std::size_t>(k)] += !same_bits(out.motion, expected[i * targets.size() + t]);
                        ++calls[static_cast<std::size_t>(k)];
                    }
        });
    for (auto& t : pool) t.join();
    for (int k = 0; k < threads; ++k) {
        CHECK(calls[static_cast<std::size_t>(k)] == rounds * 12);
        CHECK(mismatches[static_cast<std::size_t>(k)] == 0);
    }
}

TEST_CASE("set_gate refused leaves the model as it was; a workspace of another model is refused")
{
    auto model = shipped();
    const auto before = model->info();
    const std::size_t C = before.domains.size();
    // a prior weight out of range, and a posture weight out of range after valid priors
    CHECK_THROWS_AS(model->set_gate(std::vector<double>(C, 0.5), std::vector<double>(C, 0.5), std::vector<double>(C, 2.0)), value_error);
    CHECK_THROWS_AS(model->set_gate(std::vector<double>(C, 1.5), std::vector<double>(C, 0.5), std::vector<double>(C, 0.25)), value_error);
    CHECK(model->info().gate_prior == before.gate_prior);
    CHECK(model->info().gate_posture == before.gate_posture);
    CHECK(model->info().gate_motion == before.gate_motion);
    const auto other = shipped();
    auto foreign = other->make_workspace();
    const clip in = synthesize(hand_motion::pushing, emotion::neutral, 0, 3, 30.0);
    CHECK_NOTHROW((void)model->transfer(in, "sad", {}, foreign));  // same configuration: its scratch fits
    emotion_model::workspace empty;
    CHECK_NOTHROW((void)model->transfer(in, "sad", {}, empty));  // an empty workspace is filled on first use
    CHECK(empty.get() != nullptr);
}
