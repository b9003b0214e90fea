// Glove reader per-frame costs (target: far under one frame at 120 Hz, 8.3 ms, on one core): decoding
// one 64-byte report of the 7-IMU example profile and one 33-byte report of the 15-flex profile, and
// solving one hand pose from a sample of each.
#include <handemo/glove.hpp>
#include <handemo/motion/synth.hpp>

#include <benchmark/benchmark.h>

#include <string>

using namespace handemo;

namespace {

glove_profile profile(const char* name) { return read_glove_profile(std::string(HANDEMO_SOURCE_DIR) + "/examples/glove/" + name); }

struct fixture {
    glove_profile p;
    std::vector<std::vector<std::uint8_t>> reports;  // one per frame of a synthetic gripping take
    std::vector<glove_sample> samples;
    explicit fixture(const char* name) : p(profile(name))
    {
        const clip c = synthesize(hand_motion::gripping, emotion::angry, 0, 1, p.rate_hz);
        const glove_simulator sim(p, 1);
        for (std::size_t f = 0; f < c.frames; ++f) {
            samples.push_back(sim.sample(c.frame_angles(f), double(f) / p.rate_hz));
            reports.push_back(encode_reports(p, samples.back(), f, double(f) / p.rate_hz).front());
        }
    }
};

void bm_decode(benchmark::State& st, const char* name)
{
    const fixture fx(name);
    report_decoder d(fx.p);
    glove_sample s;
    std::size_t i = 0;
    std::uint64_t tick = 0;
    for (auto _ : st) {
        // keep the counter and the clock advancing: re-encode is outside the timed loop, so restart the
        // decoder when the take wraps
        if (i == fx.reports.size()) {
            st.PauseTiming();
            d = report_decoder(fx.p);
            i = 0;
            st.ResumeTiming();
        }
        const auto r = d.decode(fx.reports[i++], 0, s);
        benchmark::DoNotOptimize(r.frame);
        ++tick;
    }
    st.counters["reports/s"] = benchmark::Counter(static_cast<double>(tick), benchmark::Counter::kIsRate);
}

void bm_solve(benchmark::State& st, const char* name)
{
    const fixture fx(name);
    std::vector<double> flat(hand_joint_count * 3, 0.0);
    const glove_simulator sim(fx.p, 1);
    const hand_solver solver(fx.p, fx.p.imus.empty() ? default_calibration(fx.p)
                                                      : calibrate_glove(fx.p, std::vector<glove_sample>{sim.sample(flat.data(), 0)}));
    std::vector<double> out(hand_joint_count * 3);
    std::size_t i = 0;
    for (auto _ : st) {
        solver.solve(fx.samples[i], out.data());
        benchmark::DoNotOptimize(out.data());
        i = i + 1 == fx.samples.size() ? 0 : i + 1;
    }
    st.counters["frames/s"] = benchmark::Counter(static_cast<double>(st.iterations()), benchmark::Counter::kIsRate);
}

}  // namespace

BENCHMARK_CAPTURE(bm_decode, imu7, "imu7_example.json");
BENCHMARK_CAPTURE(bm_decode, flex15, "flex15_example.json");
BENCHMARK_CAPTURE(bm_solve, imu7, "imu7_example.json");
BENCHMARK_CAPTURE(bm_solve, flex15, "flex15_example.json");

BENCHMARK_MAIN();
