// BVH and CSV on the real files of ../shared/data (label shared-data: without the data this program exits
// 77 and is reported as skipped, see tests/test_main.cpp): every Bandai clip (64) and the Xia clip
// read, values land in the right joint and component, read-write-read round trips (BVH within 1e-4, CSV
// exact).
#include <doctest/doctest.h>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/csv.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "helpers.hpp"

// run by `<program> --shared-data` only (tests/test_main.cpp)
TEST_SUITE_BEGIN("shared-data");

namespace fs = std::filesystem;
using namespace handemo;
using handemo::test::check_same_skeleton;

namespace {

const fs::path shared_dir = HANDEMO_SHARED_DIR;

std::vector<fs::path> bandai_files()
{
    std::vector<fs::path> v;
    for (const auto& e : fs::directory_iterator(shared_dir / "data" / "bandai"))
        if (e.path().extension() == ".bvh") v.push_back(e.path());
    std::sort(v.begin(), v.end());
    return v;
}

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b)
{
    REQUIRE(a.size() == b.size());
    double m = 0;
    for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
    return m;
}

}  // namespace

TEST_CASE("bvh: every Bandai clip reads with 22 joints, 6 ZXY channels each, 30 fps")
{
    const auto files = bandai_files();
    REQUIRE(files.size() == 64);
    for (const auto& p : files) {
        CAPTURE(p);
        const clip c = read_bvh(p);
        CHECK(c.joint_count() == 22);
        CHECK(c.fps == 30.0);
        CHECK(c.frames > 0);
        for (const auto& j : c.skel.joints) {
            const std::vector<channel> zxy{channel::xposition, channel::yposition, channel::zposition,
                                           channel::zrotation, channel::xrotation, channel::yrotation};
            CHECK(j.channels == zxy);
        }
        CHECK_NOTHROW(c.validate(p.string()));
    }
}

TEST_CASE("bvh: values land in the right joint and component")
{
    const clip c = read_bvh(shared_dir / "data/bandai/dataset-1_bow_active_001.bvh");
    CHECK(c.frames == 128);
    CHECK(c.skel.joints[0].name == "joint_Root");
    CHECK(c.skel.joints[1].name == "Hips");
    CHECK(c.skel.joints[1].parent == 0);
    CHECK(c.skel.joints[1].offset[2] == doctest::Approx(-452.225));
    // Row 1: "0 0 0 0 0 -0 | -0.53398 93.523 -9.02016 88.9893 -5.14473 4.5493 | ..." (X Y Z pos, Z X Y rot)
    CHECK(c.position(0, 1, 0) == doctest::Approx(-0.53398));
    CHECK(c.position(0, 1, 1) == doctest::Approx(93.523));
    CHECK(c.position(0, 1, 2) == doctest::Approx(-9.02016));
    CHECK(c.angle(0, 1, 2) == doctest::Approx(88.9893));
    CHECK(c.angle(0, 1, 0) == doctest::Approx(-5.14473));
    CHECK(c.angle(0, 1, 1) == doctest::Approx(4.5493));
    CHECK(c.duration() == doctest::Approx(128.0 / 30.0));

    const clip x = read_bvh(shared_dir / "data/xia/neutral_16_000.bvh");
    CHECK(x.joint_count() == 31);
    CHECK(x.fps == 120.0);
    CHECK(x.frames == 150);
    CHECK(x.skel.joints[0].channels.size() == 6);
    for (std::size_t j = 1; j < x.joint_count(); ++j) {
        CHECK(x.skel.joints[j].channels.size() == 3);
        CHECK(x.skel.joints[j].rotation_order() == std::array<axis, 3>{axis::z, axis::y, axis::x});
    }
    // "19.939872 16.850014 1.430627 162.659769 -85.805601 -111.407595" (X Y Z pos, Z Y X rot)
    CHECK(x.position(0, 0, 0) == doctest::Approx(19.939872));
    CHECK(x.position(0, 0, 2) == doctest::Approx(1.430627));
    CHECK(x.angle(0, 0, 2) == doctest::Approx(162.659769));
    CHECK(x.angle(0, 0, 1) == doctest::Approx(-85.805601));
    CHECK(x.angle(0, 0, 0) == doctest::Approx(-111.407595));
    // Joints without position channels carry their OFFSET as position.
    CHECK(x.position(3, 2, 0) == doctest::Approx(x.skel.joints[2].offset[0]));
    CHECK(x.skel.joints[5].end_site.has_value());
}

TEST_CASE("bvh: read-write-read round trip of every real file is equal within 1e-4")
{
    auto files = bandai_files();
    files.push_back(shared_dir / "data/xia/neutral_16_000.bvh");
    const fs::path dir = fs::temp_directory_path() / ("handemo_formats_bvh_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const auto t0 = std::chrono::steady_clock::now();
    for (const auto& p : files) {
        CAPTURE(p);
        const clip a = read_bvh(p);
        const fs::path out = dir / p.filename();
        write_bvh(out, a);
        const clip b = read_bvh(out);
        check_same_skeleton(a.skel, b.skel, 1e-6);
        CHECK(b.frames == a.frames);
        CHECK(b.fps == a.fps);
        CHECK(max_abs_diff(a.angles, b.angles) <= 1e-4);
        CHECK(max_abs_diff(a.positions, b.positions) <= 1e-4);
    }
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    MESSAGE("round trip of " << files.size() << " files: " << secs << " s");
    fs::remove_all(dir);
}

TEST_CASE("csv: round trip of real clips is exact (Bandai with underscores in names, Xia)")
{
    const fs::path dir = fs::temp_directory_path() / ("handemo_formats_csv_" + std::to_string(::getpid()));
    for (const fs::path& p : {shared_dir / "data/bandai/dataset-1_walk_sad_002.bvh", shared_dir / "data/xia/neutral_16_000.bvh"}) {
        CAPTURE(p);
        const clip a = read_bvh(p);
        const fs::path out = dir / (p.stem().string() + ".csv");
        write_csv(out, a);
        const clip b = read_csv(out, a.skel);
        CHECK(b.frames == a.frames);
        CHECK(b.fps == a.fps);
        CHECK(b.angles == a.angles);
        CHECK(b.positions == a.positions);
    }
    fs::remove_all(dir);
}

TEST_SUITE_END();
