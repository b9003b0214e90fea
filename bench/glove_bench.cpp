// Glove reader per-frame costs (target: far under one frame at 120 Hz, 8.3 ms, on one core): decoding
// one 64-byte report of the 7-IMU example profile and one 33-byte report of the 15-flex profile, and
// solving one hand pose from a sample of each; decoding one message of each glove protocol (a Senso JSON
// line, an OpenGloves alpha line with per-joint values, a 5DT Data Glove 14 Ultra report); and the latency
// from a Senso line written by a loopback TCP server to its decoded sample on the consumer's side of the
// reader thread.
#include <handemo/glove.hpp>
#include <handemo/motion/synth.hpp>

#include <benchmark/benchmark.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <string>
#include <thread>

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

/// One message per frame of a gripping take for glove family `kind` (senso, opengloves, 5dt).
struct protocol_fixture {
    glove_choice c;
    std::vector<std::vector<std::uint8_t>> messages;
    explicit protocol_fixture(const char* kind) : c(choose_glove(kind))
    {
        const clip take = synthesize(hand_motion::gripping, emotion::angry, 0, 1, c.profile.rate_hz);
        const glove_simulator sim(c.profile, 1);
        for (std::size_t f = 0; f < take.frames; ++f)
            messages.push_back(encode_messages(c, sim.sample(take.frame_angles(f), 0), f, double(f) / c.profile.rate_hz).front());
    }
};

void bm_decode_protocol(benchmark::State& st, const char* kind)
{
    const protocol_fixture fx(kind);
    const auto d = make_decoder(fx.c);
    glove_sample s;
    std::size_t i = 0, bytes = 0;
    for (auto _ : st) {
        const auto r = d->decode(fx.messages[i], 0, s);
        benchmark::DoNotOptimize(r.frame);
        bytes += fx.messages[i].size();
        i = i + 1 == fx.messages.size() ? 0 : i + 1;
    }
    st.counters["messages/s"] = benchmark::Counter(static_cast<double>(st.iterations()), benchmark::Counter::kIsRate);
    st.counters["bytes/message"] = static_cast<double>(bytes) / static_cast<double>(std::max<std::int64_t>(st.iterations(), 1));
}

/// A Senso line from a loopback TCP server to the decoded sample behind the reader thread, one at a time.
void bm_senso_loopback_latency(benchmark::State& st)
{
    const protocol_fixture fx("senso");
    const int lfd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET, a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(lfd, reinterpret_cast<sockaddr*>(&a), sizeof a);
    socklen_t len = sizeof a;
    ::getsockname(lfd, reinterpret_cast<sockaddr*>(&a), &len);
    ::listen(lfd, 1);
    int server = -1;
    std::thread acceptor([&] { server = ::accept(lfd, nullptr, nullptr); });
    glove_reader reader(std::make_unique<tcp_transport>("127.0.0.1:" + std::to_string(ntohs(a.sin_port))),
                        {.capacity = 1024, .poll = std::chrono::milliseconds(50)});
    acceptor.join();
    const int one = 1;
    ::setsockopt(server, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);  // a glove's server sends each line at once
    senso_decoder d;
    glove_sample s;
    std::size_t i = 0;
    for (auto _ : st) {
        std::string line(fx.messages[i].begin(), fx.messages[i].end());
        line += '\n';
        if (::send(server, line.data(), line.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(line.size())) st.SkipWithError("send failed");
        std::optional<hid_report> r;
        while (!(r = reader.read(std::chrono::milliseconds(100)))) {
        }
        benchmark::DoNotOptimize(d.decode(r->bytes, r->host_time, s).frame);
        i = i + 1 == fx.messages.size() ? 0 : i + 1;
    }
    ::close(server);
    ::close(lfd);
}

}  // namespace

BENCHMARK_CAPTURE(bm_decode_protocol, senso, "senso");
BENCHMARK_CAPTURE(bm_decode_protocol, opengloves, "opengloves");
BENCHMARK_CAPTURE(bm_decode_protocol, fivedt14, "5dt");
BENCHMARK(bm_senso_loopback_latency)->UseRealTime();
BENCHMARK_CAPTURE(bm_decode, imu7, "imu7_example.json");
BENCHMARK_CAPTURE(bm_decode, flex15, "flex15_example.json");
BENCHMARK_CAPTURE(bm_solve, imu7, "imu7_example.json");
BENCHMARK_CAPTURE(bm_solve, flex15, "flex15_example.json");

BENCHMARK_MAIN();
