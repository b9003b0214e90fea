// BVH and CSV readers never size a clip from a count the file declares (Frames:) or from its line count
// before the rows are parsed: a file of many joints and many one-token rows must be refused at its first
// row without asking for frames x joints x 3 values. This program replaces the global operator new to
// record the largest single allocation.
#include <doctest/doctest.h>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/csv.hpp>

#include <atomic>
#include <cstdlib>
#include <new>
#include <string>

#include "../alloc_hook.hpp"

using namespace handemo;

namespace {

constexpr std::size_t joints = 400, rows = 4000;
// What sizing the clip from the rows would ask for: one frames x joints x 3 array of doubles (38 MB).
constexpr std::size_t clip_bytes = rows * joints * 3 * sizeof(double);

/// A BVH header with `joints` joints (a root and joints-1 children), Frames: rows.
std::string many_joint_header()
{
    std::string s = "HIERARCHY\nROOT R\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n";
    for (std::size_t j = 1; j < joints; ++j)
        s += " JOINT J" + std::to_string(j) + "\n {\n  OFFSET 0 1 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n }\n";
    return s + "}\nMOTION\nFrames: " + std::to_string(rows) + "\nFrame Time: 0.04\n";
}

}  // namespace

TEST_CASE("bvh: one-token rows under a large skeleton are refused without allocating the clip")
{
    std::string text = many_joint_header();
    for (std::size_t r = 0; r < rows; ++r) text += "1\n";
    handemo_test::alloc_largest = 0;
    CHECK_THROWS_WITH_AS((void)parse_bvh(text, "big.bvh"), doctest::Contains("row has 1 values"), format_error);
    CHECK(handemo_test::alloc_largest < clip_bytes / 100);
}

TEST_CASE("csv: one-field rows under a large skeleton are refused without allocating the clip")
{
    std::string one_frame = many_joint_header();
    one_frame.replace(one_frame.find("Frames: "), std::string("Frames: " + std::to_string(rows)).size(), "Frames: 1");
    for (std::size_t k = 0; k < joints * 3 + 3; ++k) one_frame += "0 ";
    const clip c = parse_bvh(one_frame + "\n", "sk.bvh");
    const std::string csv = to_csv_string(c);
    std::string text = csv.substr(0, csv.find('\n', csv.find("frame,")) + 1);  // fps comment and header
    for (std::size_t r = 0; r < rows; ++r) text += "0\n";
    handemo_test::alloc_largest = 0;
    CHECK_THROWS_WITH_AS((void)parse_csv(text, "big.csv", c.skel), doctest::Contains("row has 1 fields"), format_error);
    CHECK(handemo_test::alloc_largest < clip_bytes / 100);
}
