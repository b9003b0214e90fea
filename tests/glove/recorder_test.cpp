// The recorder through the fake and replay transports: steady-rate output from device timestamps,
// dropped reports counted, garbage skipped with warnings, timeouts, disconnects with and without a
// reconnect, the BVH on disk valid at every flush and after a failure, the raw stream and its replay.
#include "helpers.hpp"

#include <handemo/motion/synth.hpp>

#include <doctest/doctest.h>

#include <filesystem>

using namespace handemo;
using namespace glove_test;

namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const char* name)
{
    const auto d = fs::temp_directory_path() / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

/// Feeds `n` reports of the gripping motion (100 Hz device clock from `ms0`), skipping the ticks in `drop`.
void feed(fake_transport& t, const glove_profile& p, const glove_simulator& sim, std::uint64_t tick0, std::size_t n, std::uint32_t ms0,
          double host0, const std::vector<std::uint64_t>& drop = {})
{
    static const clip c = synthesize(hand_motion::gripping, emotion::neutral, 0, 1, 100.0);
    for (std::uint64_t i = 0; i < n; ++i) {
        const std::uint64_t tick = tick0 + i;
        if (std::find(drop.begin(), drop.end(), tick) != drop.end()) continue;
        static const std::vector<double> flat(hand_joint_count * 3, 0.0);  // the first 0.5 s: flat, for the calibration
        const auto s = sim.sample(tick < 50 ? flat.data() : c.frame_angles(tick % c.frames), 0);
        for (auto& b : encode_reports(p, s, tick, (ms0 + 10.0 * double(i)) / 1000.0)) t.push(std::move(b), host0 + 0.01 * double(i));
    }
}

}  // namespace

TEST_CASE("record through the fake transport: rate, drops, garbage, timeouts, reconnect")
{
    const auto dir = temp_dir("handemo_glove_rec");
    const auto p = imu_profile();
    const glove_simulator sim(p, 4);
    fake_transport t("fake glove #1");
    feed(t, p, sim, 0, 100, 5000, 100.0, {40, 41, 42});  // 1 s, three reports lost
    t.push({1, 2, 3}, 101.0);                            // short
    t.push(std::vector<std::uint8_t>(64, 7), 101.0);     // wrong id
    auto zero = imu_report(101, 6000, std::vector<quat>(7, quat{0, 0, 0, 0}));
    t.push(zero, 101.0);                                 // non-unit quaternions
    t.push_timeout();
    t.push_timeout();
    feed(t, p, sim, 100, 50, 6000, 101.0);               // 0.5 s more
    t.push_disconnect(2);                                // two failed attempts, then back
    feed(t, p, sim, 0, 50, 0, 101.8);                    // the device restarted: its counter and clock too
    t.close();

    record_options o;
    o.fps = 30;
    o.out = dir / "take.bvh";
    o.raw = dir / "take.raw";
    o.reconnect_window = 5;
    o.reconnect_poll = 0.001;
    glove_recorder rec(t, p, std::nullopt, o);
    std::vector<std::string> warnings;
    rec.on_warning = [&](const std::string& w) { warnings.push_back(w); };
    rec.run();
    const auto& st = rec.stats();
    CHECK(st.reports == 100 - 3 + 3 + 50 + 50);
    CHECK(st.samples == 197);
    CHECK(st.dropped == 3);
    CHECK(st.malformed == 3);
    CHECK(st.faults[static_cast<std::size_t>(report_fault::short_report)] == 1);
    CHECK(st.faults[static_cast<std::size_t>(report_fault::unknown_id)] == 1);
    CHECK(st.faults[static_cast<std::size_t>(report_fault::non_unit_quaternion)] == 1);
    CHECK(st.timeouts == 2);
    CHECK(st.reconnects == 1);
    CHECK(t.reconnect_attempts == 3);
    // 1.5 s on the device clock, then the gap from the host clock (0.3 s), then 0.49 s
    CHECK(st.duration == doctest::Approx(1.49 + 0.31 + 0.49).epsilon(1e-6));
    REQUIRE(warnings.size() >= 5);
    CHECK(warnings[0].find("skipped: report id 1 has 3 bytes") != std::string::npos);
    CHECK(warnings[3].find("fake glove #1 disconnected") != std::string::npos);
    CHECK(warnings[4].find("reconnected") != std::string::npos);

    const clip c = read_bvh(o.out);
    CHECK(c.frames == static_cast<std::size_t>(std::floor(st.duration * 30 + 1e-9)) + 1);
    CHECK(c.fps == doctest::Approx(30));
    CHECK(is_hand_skeleton(c.skel));
    CHECK(st.gap_frames >= 1);  // the frames in the 40 ms loss and the reconnect gap are counted
    CHECK(st.gap_frames <= 12);
    // the pose moves (gripping): the index PIP spans a wide range
    double lo = 1e9, hi = -1e9;
    for (std::size_t f = 0; f < c.frames; ++f) lo = std::min(lo, c.angle(f, hand_index::finger_joint(1, 2), 0)), hi = std::max(hi, c.angle(f, hand_index::finger_joint(1, 2), 0));
    CHECK(hi - lo > 30);

    // the raw stream replays to the same recording
    replay_transport rp(o.raw);
    record_options o2 = o;
    o2.out = dir / "replayed.bvh";
    o2.raw.clear();
    glove_recorder rec2(rp, p, std::nullopt, o2);
    rec2.run();
    CHECK(rp.size() == st.reports + 1);  // and the reconnect marker
    CHECK(rec2.stats().samples == 197);
    CHECK(rec2.stats().reconnects == 1);
    CHECK(rec2.stats().malformed == 3);
    CHECK(rec2.stats().duration == doctest::Approx(st.duration).epsilon(1e-9));
    const clip c2 = read_bvh(o2.out);
    REQUIRE(c2.frames == c.frames);
    for (std::size_t i = 0; i < c.angles.size(); ++i) REQUIRE(c2.angles[i] == doctest::Approx(c.angles[i]).epsilon(1e-5));
    fs::remove_all(dir);
}

TEST_CASE("a disconnect without reconnect: device_error naming the device, and the BVH holds the take")
{
    const auto dir = temp_dir("handemo_glove_disc");
    const auto p = imu_profile();
    const glove_simulator sim(p, 4);
    fake_transport t("glove on /dev/hidraw9");
    feed(t, p, sim, 0, 300, 0, 0.0);
    t.push_disconnect(1000);
    record_options o;
    o.out = dir / "take.bvh";
    o.flush_seconds = 0.5;
    {
        glove_recorder rec(t, p, std::nullopt, o);
        CHECK_THROWS_WITH_AS(rec.run(), doctest::Contains("glove on /dev/hidraw9 disconnected"), device_error);
        CHECK(read_bvh(o.out).frames == 180);  // 2.99 s at 60 fps, written before the error left run()
    }
    // the same with a window that runs out
    fake_transport t2("glove B");
    feed(t2, p, sim, 0, 100, 0, 0.0);
    t2.push_disconnect(1000);
    o.reconnect_window = 0.05;
    o.reconnect_poll = 0.01;
    glove_recorder rec2(t2, p, std::nullopt, o);
    CHECK_THROWS_WITH_AS(rec2.run(), doctest::Contains("no reconnect within"), device_error);
    CHECK(t2.reconnect_attempts >= 2);
    CHECK(read_bvh(o.out).frames == 60);
    fs::remove_all(dir);
}

TEST_CASE("the BVH on disk is valid while recording, flushed in chunks")
{
    const auto dir = temp_dir("handemo_glove_flush");
    const auto p = imu_profile();
    const glove_simulator sim(p, 4);
    fake_transport t;
    feed(t, p, sim, 0, 400, 0, 0.0);
    t.close();
    record_options o;
    o.out = dir / "take.bvh";
    o.flush_seconds = 1;
    glove_recorder rec(t, p, std::nullopt, o);
    std::size_t checks = 0, last = 0;
    while (rec.step()) {
        if (fs::exists(o.out) && rec.stats().samples % 50 == 0) {
            const clip c = read_bvh(o.out);  // parses at any moment
            CHECK(c.frames >= last);
            last = c.frames;
            ++checks;
        }
    }
    rec.flush();
    CHECK(checks >= 4);
    CHECK(read_bvh(o.out).frames == 240);
    fs::remove_all(dir);
}

TEST_CASE("seconds limit, keep_seconds window and a truncated raw file")
{
    const auto dir = temp_dir("handemo_glove_misc");
    const auto p = imu_profile();
    const glove_simulator sim(p, 4);
    fake_transport t;
    feed(t, p, sim, 0, 500, 0, 0.0);
    record_options o;
    o.seconds = 4.5;  // past twice keep_seconds, where the recorder trims
    o.keep_seconds = 1;
    o.raw = dir / "r.raw";
    glove_recorder rec(t, p, std::nullopt, o);
    rec.run();
    CHECK(rec.stats().duration >= 4.5);
    CHECK(rec.stats().duration < 4.5 + 0.011);
    // only the newest 1..2 s of poses are kept: the oldest ones were cut
    const auto times = rec.times();
    REQUIRE(times.size() >= 2);
    CHECK(times.size() < rec.stats().samples);
    CHECK(times.back() - times.front() >= 1.0 - 1e-9);
    CHECK(times.back() - times.front() <= 2.0 + 1e-9);
    CHECK(times.front() >= 4.5 - 2.0 - 1e-9);
    CHECK(rec.poses().size() == times.size() * hand_joint_count * 3);
    const clip last = rec.take(1.0);
    CHECK(last.frames == 61);
    // cut the raw file inside its last record: the replay ignores that record and says where
    const auto size = fs::file_size(o.raw);
    fs::resize_file(o.raw, size - 5);
    replay_transport rp(o.raw);
    CHECK(rp.size() == rec.stats().reports - 1);
    CHECK(rp.truncated() > 0);
    fs::remove_all(dir);
}
