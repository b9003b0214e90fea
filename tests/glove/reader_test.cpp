// The reader thread under ThreadSanitizer (label tsan): a glove faster than its consumer. Every report the
// producer made is either consumed or counted as an overrun, in order, each with the producer's own time
// stamp and an arrival stamp that never runs backwards; the recorder's accessors are read from a second
// thread while it records. TSan fails the program on a data race.
#include <handemo/glove.hpp>

#include <doctest/doctest.h>

#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

using namespace handemo;

namespace {

/// A glove that makes `n` reports as fast as it is read (about one per `period`), each carrying its index
/// and stamped with the host time when it was made; then it is finished.
class counting_glove : public glove_transport {
public:
    counting_glove(std::size_t n, std::chrono::microseconds period) : n_(n), period_(period), made_(n) {}
    std::string name() const override { return "counting glove"; }
    std::optional<hid_report> read(std::chrono::milliseconds) override
    {
        if (i_ >= n_) return std::nullopt;
        std::this_thread::sleep_for(period_);
        hid_report r;
        r.bytes = {static_cast<std::uint8_t>(i_), static_cast<std::uint8_t>(i_ >> 8), static_cast<std::uint8_t>(i_ >> 16)};
        r.host_time = made_[i_] = host_seconds();
        ++i_;
        return r;
    }
    bool finished() const override { return i_ >= n_; }
    /// Host time report i was made at (read after the reader thread has ended).
    double made(std::size_t i) const { return made_[i]; }

private:
    std::size_t n_, i_ = 0;
    std::chrono::microseconds period_;
    std::vector<double> made_;
};

}  // namespace

TEST_CASE("a consumer slower than the glove: overruns counted, order and time stamps kept")
{
    constexpr std::size_t n = 3000;
    auto g = std::make_unique<counting_glove>(n, std::chrono::microseconds(50));
    const auto* glove = g.get();
    glove_reader reader(std::move(g), {.capacity = 64, .poll = std::chrono::milliseconds(5)});
    std::size_t consumed = 0, last_index = 0;
    double last_arrival = 0;
    bool first = true, order_ok = true, arrival_ok = true;
    std::vector<std::pair<std::size_t, double>> seen;
    while (!reader.finished()) {
        const auto r = reader.read(std::chrono::milliseconds(20));
        if (!r) continue;
        const std::size_t i = r->bytes[0] | (std::size_t(r->bytes[1]) << 8) | (std::size_t(r->bytes[2]) << 16);
        order_ok = order_ok && (first || i > last_index);
        arrival_ok = arrival_ok && r->arrival >= last_arrival && r->arrival >= r->host_time;
        first = false, last_index = i, last_arrival = r->arrival;
        seen.emplace_back(i, r->host_time);
        ++consumed;
        if (consumed % 4 == 0) std::this_thread::sleep_for(std::chrono::microseconds(800));  // slower than the glove
    }
    reader.stop();
    CHECK(order_ok);
    CHECK(arrival_ok);
    CHECK(reader.received() == n);
    CHECK(reader.overruns() > 0);
    CHECK(consumed + reader.overruns() == n);
    MESSAGE(consumed, " consumed, ", reader.overruns(), " overruns");
    for (const auto& [i, t] : seen) REQUIRE(t == glove->made(i));  // the producer's own stamps
}

TEST_CASE("the recorder's accessors from another thread while it records through the reader")
{
    const glove_profile p = opengloves_profile();
    const glove_simulator sim(p);
    auto fake = std::make_unique<fake_transport>("fake opengloves");
    std::vector<double> pose(hand_joint_count * 3, 0.0);
    for (int i = 0; i < 2000; ++i) {
        pose[hand_index::finger_joint(1, 2) * 3] = i % 100;
        fake->push_line(opengloves_line(sim.sample(pose.data(), 0), 4095), i / 60.0);
    }
    fake->close();
    glove_reader reader(std::move(fake), {.capacity = 4096});
    record_options o;
    o.keep_seconds = 2;
    glove_recorder rec(reader, std::make_unique<opengloves_decoder>(4095), std::nullopt, o);
    std::atomic<bool> done{false};
    std::size_t polls = 0;
    std::thread watcher([&] {
        while (!done.load()) {
            const auto s1 = rec.stats();
            const auto t = rec.times();
            const auto s2 = rec.stats();  // read after: at least as many samples
            const auto [count, span] = rec.extent();
            if (count > 1 && polls % 16 == 0) (void)rec.take(0.5);
            CHECK(s1.samples <= s2.samples);
            CHECK(t.size() <= s2.samples);
            CHECK(span >= 0);
            ++polls;
        }
    });
    rec.run();
    done = true;
    watcher.join();
    CHECK(rec.stats().samples == 2000);
    CHECK(polls > 0);
}
