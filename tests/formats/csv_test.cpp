// Tests of the CSV motion format (real clips: shared_data_test.cpp), column matching by name in any order,
// the fps comment, and one test per malformed input (file, line and column named).
#include <doctest/doctest.h>
#include <handemo/motion/csv.hpp>

#include <filesystem>
#include <random>
#include <string>

#include <unistd.h>

namespace fs = std::filesystem;
using namespace handemo;

namespace {

const std::string tiny_bvh =
    "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n"
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "  JOINT Left_Arm\n  {\n    OFFSET 0 1 0\n    CHANNELS 3 Zrotation Xrotation Yrotation\n  }\n}\n"
    "MOTION\nFrames: 2\nFrame Time: 0.0333333\n1 2 3 4 5 6 7 8 9\n-1 -2 -3 -4 -5 -6 -7 -8 -9.25\n";

// Lines: 1 fps comment, 2 header, 3-4 rows.
const std::string tiny_csv =
    "# fps=30\n"
    "frame,Hips_px,Hips_py,Hips_pz,Hips_x,Hips_y,Hips_z,Left_Arm_x,Left_Arm_y,Left_Arm_z\n"
    "0,1,2,3,5,6,4,8,9,7\n"
    "1,-1,-2,-3,-5,-6,-4,-8,-9.25,-7\n";

void expect_error(const std::string& text, long line, const std::string& part)
{
    const skeleton sk = parse_bvh(tiny_bvh, "tiny.bvh").skel;
    CAPTURE(part);
    try {
        (void)parse_csv(text, "t.csv", sk);
        FAIL("no exception for: " << part);
    } catch (const format_error& e) {
        const std::string msg = e.what();
        CAPTURE(msg);
        CHECK(msg.rfind("csv: t.csv:" + std::to_string(line) + ": ", 0) == 0);
        CHECK(msg.find(part) != std::string::npos);
    }
}

std::string replace(std::string s, const std::string& from, const std::string& to)
{
    const auto p = s.find(from);
    REQUIRE(p != std::string::npos);
    return s.replace(p, from.size(), to);
}

}  // namespace

TEST_CASE("csv: layout with fps comment, position columns for 6-channel joints, x y z angles")
{
    const clip c = parse_bvh(tiny_bvh, "tiny.bvh");
    CHECK(to_csv_string(c) == tiny_csv);
}

TEST_CASE("csv: columns are matched by name in any order; CRLF, blanks and comments are accepted")
{
    const clip ref = parse_bvh(tiny_bvh, "tiny.bvh");
    const std::string shuffled =
        "# exported by hand\r\n# fps=120\r\n"
        "frame, Left_Arm_z,Hips_x,Hips_y,Hips_z,Left_Arm_x,Left_Arm_y,Hips_pz,Hips_py,Hips_px\r\n"
        "\r\n"
        "0,7,5,6,4,8,9,3,2,1\r\n"
        "1,-7,-5,-6,-4,-8,-9.25,-3,-2,-1\r\n";
    const clip c = parse_csv(shuffled, "s.csv", ref.skel);
    CHECK(c.fps == 120.0);
    CHECK(c.frames == 2);
    CHECK(c.angles == ref.angles);
    CHECK(c.positions == ref.positions);
    // Without the fps comment, 30 fps is assumed (documented).
    CHECK(parse_csv(tiny_csv.substr(tiny_csv.find('\n') + 1), "n.csv", ref.skel).fps == 30.0);
}

TEST_CASE("csv: a missing file is an error")
{
    CHECK_THROWS_AS((void)read_csv(fs::temp_directory_path() / "handemo_no_such_dir" / "missing.csv", skeleton{}), error);
}

TEST_CASE("csv: malformed files are format_errors naming file, line and column")
{
    expect_error(replace(tiny_csv, "Left_Arm_y", "Right_Arm_y"), 2, "unknown column 'Right_Arm_y': no joint 'Right_Arm'");
    expect_error(replace(tiny_csv, "Left_Arm_y", "Left_Arm_w"), 2, "suffix 'w' is not x, y, z, px, py or pz");
    expect_error(replace(tiny_csv, "Left_Arm_y", "LeftArmY"), 2, "unknown column 'LeftArmY'");
    expect_error(replace(tiny_csv, "Left_Arm_y", "Left_Arm_px"), 2, "joint 'Left_Arm' has no position channels");
    expect_error(replace(tiny_csv, "Left_Arm_y", "Left_Arm_x"), 2, "duplicate column 'Left_Arm_x'");
    expect_error(replace(tiny_csv, ",Hips_py", ""), 2, "missing column 'Hips_py'");
    expect_error(replace(tiny_csv, "frame,", "time,"), 2, "first column is 'time', expected 'frame'");
    expect_error(replace(tiny_csv, "0,1,2,3,5,6", "0,1,2,3,5,six"), 3, "column 'Hips_y': 'six' is not a number");
    expect_error(replace(tiny_csv, "0,1,2,3,5,6", "0,1,2,3,5,"), 3, "column 'Hips_y': '' is not a number");
    expect_error(replace(tiny_csv, "-8,-9.25", "-8,nan"), 4, "column 'Left_Arm_y': value 'nan' is not finite");
    expect_error(replace(tiny_csv, "-8,-9.25", "-8,inf"), 4, "value 'inf' is not finite");
    expect_error(replace(tiny_csv, "-8,-9.25,-7", "-8,-9.25"), 4, "row has 9 fields, expected 10");
    expect_error(replace(tiny_csv, "-8,-9.25,-7", "-8,-9.25,-7,0"), 4, "row has 11 fields, expected 10");
    expect_error(tiny_csv.substr(0, tiny_csv.find("0,1")), 2, "no data rows");
    expect_error("# fps=30\n", 1, "no header line");
    expect_error("", 1, "no header line");
    expect_error(replace(tiny_csv, "fps=30", "fps=0"), 1, "fps '0' is not a positive number");
    expect_error(replace(tiny_csv, "fps=30", "fps=fast"), 1, "fps 'fast' is not a positive number");
}

TEST_CASE("a bad skeleton is an error naming what it came with (the CSV file, the clip's source)")
{
    skeleton bad = parse_bvh(tiny_bvh, "tiny.bvh").skel;
    bad.joints[1].parent = 5;  // a parent after its child
    CHECK_THROWS_WITH_AS(parse_csv(tiny_csv, "take.csv", bad), doctest::Contains("take.csv"), format_error);
    CHECK_THROWS_WITH_AS(parse_csv(tiny_csv, "take.csv", bad), doctest::Contains("has parent index 5"), format_error);
    clip c = parse_bvh(tiny_bvh, "tiny.bvh");
    c.skel.joints.clear();
    CHECK_THROWS_WITH_AS(c.validate("walk_angry_0.bvh"), doctest::Contains("walk_angry_0.bvh"), format_error);
    CHECK_THROWS_WITH_AS(c.validate("walk_angry_0.bvh"), doctest::Contains("no joints"), format_error);
}

TEST_CASE("csv: writer refuses names that would break the format")
{
    clip c = parse_bvh(tiny_bvh, "tiny.bvh");
    c.skel.joints[1].name = "a,b";
    CHECK_THROWS_AS((void)to_csv_string(c), value_error);
}

TEST_CASE("csv: every truncation and random corruption gives a clip or a format_error, never anything else")
{
    const skeleton sk = parse_bvh(tiny_bvh, "tiny.bvh").skel;
    for (std::size_t n = 0; n < tiny_csv.size(); ++n) {
        CAPTURE(n);
        try {
            const clip c = parse_csv(tiny_csv.substr(0, n), "cut.csv", sk);
            CHECK_NOTHROW(c.validate());
            CHECK(c.frames >= 1);
        } catch (const format_error&) {
        }
    }
    std::mt19937 rng(777);
    const std::string alphabet = "0123456789-+.eE,_ xyzp\n\r#naif=";
    std::size_t refused = 0;
    for (int it = 0; it < 3000; ++it) {
        std::string s = tiny_csv;
        for (int e = 0; e < 1 + static_cast<int>(rng() % 3); ++e) s[rng() % s.size()] = alphabet[rng() % alphabet.size()];
        clip c;
        try {
            c = parse_csv(s, "fuzz.csv", sk);
        } catch (const format_error&) {
            ++refused;
            continue;
        }
        CHECK_NOTHROW(c.validate());
    }
    CHECK(refused > 0);
}
