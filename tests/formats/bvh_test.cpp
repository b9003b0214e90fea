// Tests of the BVH reader and writer: a hand-written file with unusual layout, the writer's layout, and one
// test per malformed input. The real Bandai and Xia files: shared_data_test.cpp (label shared-data).
#include <doctest/doctest.h>
#include <handemo/motion/bvh.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "helpers.hpp"

namespace fs = std::filesystem;
using namespace handemo;
using handemo::test::check_same_skeleton;

namespace {

// A small file with CRLF line ends, tabs and runs of spaces, a 6-channel root in an unusual interleaved
// order, a 3-channel joint in XYZ order, an End Site, a second branch and a joint name with a space.
const std::string small_bvh =
    "HIERARCHY\r\n"
    "ROOT  Hips\r\n"
    "{\r\n"
    "\tOFFSET   1.5\t2 -3\r\n"
    "\tCHANNELS 6 Yrotation Xposition Zrotation Yposition Xrotation Zposition\r\n"
    "\tJOINT Left Arm\r\n"
    "\t{\r\n"
    "\t\tOFFSET 0 1 0\r\n"
    "\t\tCHANNELS 3 Xrotation Yrotation Zrotation\r\n"
    "\t\tEnd Site\r\n"
    "\t\t{\r\n"
    "\t\t\tOFFSET 0 0.5 0\r\n"
    "\t\t}\r\n"
    "\t}\r\n"
    "\tJOINT Head {\r\n"
    "\t\tOFFSET 0 0 1\r\n"
    "\t\tCHANNELS 3 Zrotation Yrotation Xrotation\r\n"
    "\t}\r\n"
    "}\r\n"
    "MOTION\r\n"
    "Frames:   2\r\n"
    "Frame Time: 0.04\r\n"
    "10 1 20 2 30 3   4 5 6  7 8 9\r\n"
    "\r\n"
    "-10\t-1 -20 -2 -30 -3 +4 5e0 6 7 8 9.5  \r\n";

/// Checks that parsing `text` throws a format_error whose message starts with "bvh: t.bvh:<line>:" and
/// contains `part`.
void expect_error(const std::string& text, long line, const std::string& part)
{
    CAPTURE(part);
    try {
        (void)parse_bvh(text, "t.bvh");
        FAIL("no exception for: " << part);
    } catch (const format_error& e) {
        const std::string msg = e.what();
        CAPTURE(msg);
        CHECK(msg.rfind("bvh: t.bvh:" + std::to_string(line) + ": ", 0) == 0);
        CHECK(msg.find(part) != std::string::npos);
    }
}

std::string replace(std::string s, const std::string& from, const std::string& to)
{
    const auto p = s.find(from);
    REQUIRE(p != std::string::npos);
    return s.replace(p, from.size(), to);
}

const std::string tiny =  // lines: 1 HIERARCHY .. 12 MOTION, 13 Frames, 14 Frame Time, 15-16 rows
    "HIERARCHY\n"
    "ROOT Hips\n"
    "{\n"
    "  OFFSET 0 0 0\n"
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "  JOINT Spine\n"
    "  {\n"
    "    OFFSET 0 1 0\n"
    "    CHANNELS 3 Zrotation Xrotation Yrotation\n"
    "  }\n"
    "}\n"
    "MOTION\n"
    "Frames: 2\n"
    "Frame Time: 0.0333333\n"
    "1 2 3 4 5 6 7 8 9\n"
    "1 2 3 4 5 6 7 8 9\n";

}  // namespace

TEST_CASE("bvh: CRLF, tabs, interleaved channel orders, names with spaces, blank rows")
{
    const clip c = parse_bvh(small_bvh, "small.bvh");
    REQUIRE(c.joint_count() == 3);
    CHECK(c.skel.joints[1].name == "Left Arm");
    CHECK(c.skel.joints[2].name == "Head");
    CHECK(c.skel.joints[2].parent == 0);
    CHECK(c.skel.joints[0].offset == vec3{1.5, 2, -3});
    REQUIRE(c.skel.joints[1].end_site.has_value());
    CHECK((*c.skel.joints[1].end_site)[1] == 0.5);
    CHECK_FALSE(c.skel.joints[2].end_site.has_value());
    CHECK(c.fps == 25.0);
    CHECK(c.frames == 2);
    // Root: Yrot Xpos Zrot Ypos Xrot Zpos = 10 1 20 2 30 3
    CHECK(c.angle(0, 0, 1) == 10);
    CHECK(c.angle(0, 0, 2) == 20);
    CHECK(c.angle(0, 0, 0) == 30);
    CHECK(c.position(0, 0, 0) == 1);
    CHECK(c.position(0, 0, 1) == 2);
    CHECK(c.position(0, 0, 2) == 3);
    CHECK(c.skel.joints[0].rotation_order() == std::array<axis, 3>{axis::y, axis::z, axis::x});
    CHECK(c.angle(1, 1, 0) == 4);  // "+4" with a plus sign
    CHECK(c.angle(1, 1, 1) == 5);
    CHECK(c.angle(1, 2, 2) == 7);  // Head ZYX
    CHECK(c.angle(1, 2, 0) == 9.5);
    CHECK(c.position(1, 2, 2) == 1);  // Head has no position channel: offset

    // Round trip keeps channel order, names and values.
    const clip r = parse_bvh(to_bvh_string(c), "r.bvh");
    check_same_skeleton(c.skel, r.skel, 0);
    CHECK(r.angles == c.angles);
    CHECK(r.positions == c.positions);
    CHECK(r.fps == c.fps);
}

TEST_CASE("bvh: writer layout is the conventional one")
{
    const clip c = parse_bvh(tiny, "tiny.bvh");
    const std::string s = to_bvh_string(c);
    CHECK(s.rfind("HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 0 0\n\tCHANNELS 6 Xposition Yposition Zposition "
                  "Zrotation Xrotation Yrotation\n\tJOINT Spine\n\t{\n\t\tOFFSET 0 1 0\n\t\tCHANNELS 3 "
                  "Zrotation Xrotation Yrotation\n\t}\n}\nMOTION\nFrames:\t2\nFrame Time:\t",
                  0) == 0);
    CHECK(s.find("\n1 2 3 4 5 6 7 8 9\n1 2 3 4 5 6 7 8 9\n") != std::string::npos);
    // precision is digits after the point.
    clip d = c;
    d.angle(0, 1, 0) = 1.23456789;
    CHECK(to_bvh_string(d, 2).find(" 1.23 ") != std::string::npos);
    CHECK_THROWS_AS((void)to_bvh_string(d, 30), value_error);
    // A clip whose joints are not depth-first is written depth-first and reads back as such.
    skeleton sk;
    sk.joints.resize(4);
    sk.joints[0].name = "r", sk.joints[0].parent = -1;
    sk.joints[1].name = "a", sk.joints[1].parent = 0;
    sk.joints[2].name = "b", sk.joints[2].parent = 0;
    sk.joints[3].name = "a1", sk.joints[3].parent = 1;
    sk.joints[3].end_site = vec3{0, 1, 0};
    clip e = clip::make(sk, 1, 30);
    for (std::size_t j = 0; j < 4; ++j) e.angle(0, j, 0) = static_cast<double>(j);
    const clip f = parse_bvh(to_bvh_string(e), "e.bvh");
    REQUIRE(f.joint_count() == 4);
    CHECK(f.skel.joints[2].name == "a1");
    CHECK(f.skel.joints[2].parent == 1);
    CHECK(f.angle(0, 2, 0) == 3);
    CHECK(f.skel.joints[3].name == "b");
    CHECK(f.angle(0, 3, 0) == 2);
    CHECK(f.skel.joints[2].end_site.has_value());
    // A joint whose channels are not 3 rotations (+3 positions) cannot be written.
    e.skel.joints[2].channels = {channel::xrotation, channel::xrotation, channel::zrotation};
    CHECK_THROWS_AS((void)to_bvh_string(e), value_error);
}

TEST_CASE("bvh: deep nesting uses an explicit stack (no recursion)")
{
    const std::size_t depth = 1500;
    std::string s = "HIERARCHY\nROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n";
    for (std::size_t i = 1; i < depth; ++i)
        s += "JOINT j" + std::to_string(i) + "\n{\nOFFSET 0 1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n";
    s += "End Site\n{\nOFFSET 0 1 0\n}\n";
    for (std::size_t i = 0; i < depth; ++i) s += "}\n";
    s += "MOTION\nFrames: 1\nFrame Time: 0.01\n";
    for (std::size_t i = 0; i < depth; ++i) s += "1 2 3 ";
    s += "\n";
    const clip c = parse_bvh(s, "deep.bvh");
    CHECK(c.joint_count() == depth);
    CHECK(c.skel.joints[depth - 1].parent == static_cast<int>(depth - 2));
    CHECK(c.angle(0, depth - 1, 2) == 1);
    const clip r = parse_bvh(to_bvh_string(c), "deep2.bvh");
    CHECK(r.skel.same_topology(c.skel));
}

TEST_CASE("bvh: missing file is an io_error naming it")
{
    CHECK_THROWS_WITH_AS((void)read_bvh("/nonexistent/dir/walk.bvh"), doctest::Contains("/nonexistent/dir/walk.bvh"),
                         io_error);
}

TEST_CASE("bvh: malformed files are format_errors naming file, line and field")
{
    expect_error("", 1, "empty file");
    expect_error("HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n", 5, "unexpected end of file");
    expect_error(tiny.substr(0, tiny.find("  JOINT")), 6, "joint 'Hips' opened on line 2 is not closed");
    expect_error(tiny.substr(0, tiny.find("MOTION") + 7), 13, "unexpected end of file after MOTION");
    expect_error(tiny.substr(0, tiny.find("Frame Time")), 14, "expected Frame Time");
    expect_error(replace(tiny, "CHANNELS 3", "CHANNELS 7"), 9, "CHANNELS 7 is not 3 or 6 (joint 'Spine')");
    expect_error(replace(tiny, "CHANNELS 3", "CHANNELS x"), 9, "CHANNELS count 'x'");
    expect_error(replace(tiny, "CHANNELS 3 Zrotation", "CHANNELS 3 Wrotation"), 9, "unknown channel 'Wrotation' in joint 'Spine'");
    expect_error(replace(tiny, "3 Zrotation Xrotation", "3 Xrotation Xrotation"), 9, "Xrotation exactly once, found 2");
    expect_error(replace(tiny, "6 Xposition Yposition", "6 Xposition Xposition"), 5, "Xposition exactly once, found 2");
    expect_error(replace(tiny, "OFFSET 0 1 0", "OFFSET 0 one 0"), 8, "OFFSET of joint 'Spine': 'one' is not a number");
    expect_error(replace(tiny, "OFFSET 0 1 0", "OFFSET 0 inf 0"), 8, "'inf' is not finite");
    expect_error(replace(tiny, "OFFSET 0 1 0\n", "OFFSET 0 1 0\n    OFFSET 0 1 0\n"), 9, "second OFFSET");
    expect_error(replace(tiny, "    OFFSET 0 1 0\n", ""), 9, "joint 'Spine' has no OFFSET");
    expect_error(replace(tiny, "ROOT Hips", "ROOT"), 2, "ROOT has no name");
    expect_error(replace(tiny, "HIERARCHY", "HIERARCHIE"), 1, "expected HIERARCHY");
    expect_error(replace(tiny, "  JOINT Spine", "  BONE Spine"), 6, "found 'BONE'");
    expect_error(replace(tiny, "1 2 3 4 5 6 7 8 9\n1", "1 2 3 4 5 x 7 8 9\n1"), 15,
                 "frame 0 joint 'Hips' Yrotation: 'x' is not a number");
    expect_error(replace(tiny, "1 2 3 4 5 6 7 8 9\n1", "1 2 3 4 5 6 7 8 9\nnan"), 16, "value 'nan' is not finite");
    expect_error(replace(tiny, "1 2 3 4 5 6 7 8 9\n1", "1 2 3 4 5 6 7 8 9\n-inf"), 16, "is not finite");
    expect_error(replace(tiny, "1 2 3 4 5 6 7 8 9\n1", "1 2 3 4 5 6 7 8 9\n1e999"), 16, "is not finite");
    expect_error(replace(tiny, "Frames: 2", "Frames: 3"), 13, "Frames: 3 but the file has 2 data rows (truncated");
    expect_error(replace(tiny, "Frames: 2", "Frames: 1"), 13, "Frames: 1 but the file has 2 data rows (extra");
    expect_error(replace(tiny, "Frames: 2", "Frames: 0"), 13, "Frames: 0, a clip needs at least one frame");
    expect_error(replace(tiny, "Frames: 2", "Frames: two"), 13, "Frames: 'two' is not a non-negative integer");
    expect_error(replace(tiny, "Frames: 2", "Frames: -2"), 13, "is not a non-negative integer");
    expect_error(replace(tiny, "7 8 9\n1 2", "7 8\n1 2"), 15, "row has 8 values, expected 9");
    expect_error(replace(tiny, "7 8 9\n1 2", "7 8 9 10 11\n1 2"), 15, "row has 11 values, expected 9");
    expect_error(replace(tiny, "0.0333333", "0"), 14, "Frame Time 0 is not positive");
    expect_error(replace(tiny, "0.0333333", "-0.04"), 14, "Frame Time -0.04 is not positive");
    expect_error(replace(tiny, "0.0333333", "fast"), 14, "Frame Time: 'fast' is not a number");
    expect_error(replace(tiny, "0.0333333", "1e-310"), 14, "Frame Time 1e-310 gives a frame rate of inf");
}

TEST_CASE("bvh: absurd sizes are refused before allocating")
{
    // Frames: 10^12 with one row: refused from the row count, instantly and without a 10^12-frame buffer.
    const auto t0 = std::chrono::steady_clock::now();
    expect_error(replace(tiny, "Frames: 2", "Frames: 1000000000000"), 13, "Frames: 1000000000000 but the file has 2");
    expect_error(replace(tiny, "Frames: 2", "Frames: 99999999999999999999999"), 13, "is not a non-negative integer");
    CHECK(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < 1.0);

    // More than 10^4 joints.
    std::string s = "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n";
    for (std::size_t i = 0; i < bvh_max_joints; ++i)
        s += "JOINT j" + std::to_string(i) + "\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n}\n";
    s += "}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0\n";
    // Joint number 10001 (0-based 10000) opens on line 5 + 5 * 9999 + 1.
    expect_error(s, 5 + 5 * 9999 + 1, "more than 10000 joints");
}

TEST_CASE("bvh: every truncation and random corruption gives a clip or a format_error, never anything else")
{
    // Truncation at every byte of the small file: a prefix that ends inside the last row or earlier must
    // be refused; only prefixes that keep the whole last row may parse, and then they parse fully.
    const std::size_t last_row = small_bvh.rfind("-10\t");
    for (std::size_t n = 0; n < small_bvh.size(); ++n) {
        CAPTURE(n);
        const std::string cut = small_bvh.substr(0, n);
        try {
            const clip c = parse_bvh(cut, "cut.bvh");
            CHECK(n > last_row);
            CHECK(c.frames == 2);
            CHECK_NOTHROW(c.validate());
        } catch (const format_error&) {
        }
    }
    // Random byte changes (digits, letters, separators, braces, line breaks).
    std::mt19937 rng(12345);
    const std::string alphabet = "0123456789-+.eE xyzXYZ{}\n\r\tnaif:#";
    std::size_t parsed = 0, refused = 0;
    for (int it = 0; it < 3000; ++it) {
        std::string s = tiny;
        const int edits = 1 + static_cast<int>(rng() % 3);
        for (int e = 0; e < edits; ++e) s[rng() % s.size()] = alphabet[rng() % alphabet.size()];
        try {
            const clip c = parse_bvh(s, "fuzz.bvh");
            CHECK_NOTHROW(c.validate());
            ++parsed;
        } catch (const format_error&) {
            ++refused;
        }
    }
    MESSAGE("random corruption: " << parsed << " parsed, " << refused << " refused");
    CHECK(refused > 0);
}
