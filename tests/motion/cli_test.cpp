// End-to-end test of the handemo CLI's synth -> encode -> decode path. The CLI's path comes from the
// HANDEMO_CLI environment variable, which tests/motion/CMakeLists.txt sets to $<TARGET_FILE:handemo_cli>.
#include <handemo/image.hpp>
#include <handemo/motion.hpp>
#include <handemo/image/keyframe_image.hpp>

#include <doctest/doctest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

using namespace handemo;
namespace fs = std::filesystem;

namespace {

struct run_result {
    int rc;
    std::string out, err;
};

const fs::path& work_dir()
{
    static const fs::path d = [] {
        fs::path p = fs::temp_directory_path() / ("handemo_cli_test_" + std::to_string(::getpid()));
        fs::remove_all(p);
        fs::create_directories(p);
        return p;
    }();
    return d;
}

run_result run(const std::string& args)
{
    const char* cli = std::getenv("HANDEMO_CLI");
    REQUIRE_MESSAGE(cli != nullptr, "HANDEMO_CLI is not set (run through ctest)");
    REQUIRE_MESSAGE(fs::exists(cli), "CLI not built: " << cli);
    const fs::path o = work_dir() / "stdout.txt", e = work_dir() / "stderr.txt";
    const std::string cmd = "'" + std::string(cli) + "' " + args + " >'" + o.string() + "' 2>'" + e.string() + "'";
    const int st = std::system(cmd.c_str());
    return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, read_file(o), read_file(e)};
}

void expect_failure(const std::string& args, const std::string& needle)
{
    const run_result r = run(args);
    CHECK_MESSAGE(r.rc == 1, args);  // the README: every failure exits 1
    CHECK_MESSAGE(r.err.rfind("handemo: error: ", 0) == 0, r.err);
    CHECK_MESSAGE(r.err.find(needle) != std::string::npos, "'" << needle << "' not in: " << r.err);
    CHECK_MESSAGE(std::count(r.err.begin(), r.err.end(), '\n') == 1, r.err);
}

}  // namespace

TEST_CASE("cli: synth -> encode -> decode round trip and failure cases")
{
    const fs::path w = work_dir();
    const std::string W = "'" + w.string() + "'";
    for (const char* c : {"synth", "encode", "decode"}) CHECK(run(std::string(c) + " --help").rc == 0);

    run_result r = run("synth --out " + W + "/data --takes 1 --seed 11");
    REQUIRE_MESSAGE(r.rc == 0, r.err);
    std::size_t bvh = 0, csv = 0;
    for (const auto& e : fs::directory_iterator(w / "data")) {
        bvh += e.path().extension() == ".bvh";
        csv += e.path().extension() == ".csv";
    }
    CHECK(bvh == 35);
    CHECK(csv == 35);
    // The files hold what the library synthesises (BVH keeps 6 decimals).
    const clip lib = synthesize(hand_motion::patting, emotion::sad, 0, 11);
    const clip file = read_bvh(w / "data" / "hand_patting_sad_0.bvh");
    REQUIRE(file.frames == lib.frames);
    for (std::size_t i = 0; i < lib.angles.size(); ++i) CHECK(file.angles[i] == doctest::Approx(lib.angles[i]).epsilon(1e-5));
    CHECK(read_csv(w / "data" / "hand_patting_sad_0.csv", file.skel).frames == lib.frames);

    r = run("encode " + W + "/data --out " + W + "/img --png");
    REQUIRE_MESSAGE(r.rc == 0, r.err);
    CHECK(r.out.find("round-trip max angle error") != std::string::npos);
    MESSAGE(r.out.substr(r.out.rfind("encode:")));
    const angle_range range = load_range(w / "img" / "range.json");
    CHECK(range.keyframes == 9);
    CHECK(range.joints == 23);
    CHECK(fs::exists(w / "img" / "index.json"));

    // Decode every image at 9 frames (the keyframe times) and compare with the original's keyframes.
    double worst = 0;
    for (hand_motion m : all_hand_motions)
        for (emotion e : all_emotions) {
            const std::string stem = file_stem(m, e, 0);
            CHECK(read_image(w / "img" / (stem + ".png")) == read_image(w / "img" / (stem + ".bmp")));
            r = run("decode " + W + "/img/" + stem + ".bmp --like " + W + "/data/" + stem + ".bvh --range " + W +
                    "/img/range.json --out " + W + "/dec/" + stem + ".bvh --frames 9");
            REQUIRE_MESSAGE(r.rc == 0, r.err);
            const clip orig = read_bvh(w / "data" / (stem + ".bvh"));
            const clip dec = read_bvh(w / "dec" / (stem + ".bvh"));
            REQUIRE(dec.frames == 9);
            CHECK(dec.fps == orig.fps);
            CHECK(dec.skel.same_topology(orig.skel));
            const auto k = extract_keyframes<9>(orig);
            for (std::size_t i = 0; i < k.angles.size(); ++i) worst = std::max(worst, std::abs(dec.angles[i] - k.angles[i]));
        }
    MESSAGE("CLI encode->decode over the dataset: max keyframe angle error " << worst << " deg, bound "
                                                                              << range.max_roundtrip_error() << " deg");
    CHECK(worst <= range.max_roundtrip_error() + 2e-6);  // + BVH's 6 decimals

    // Default length: the reference's frame count and rate; natural-spline option.
    r = run("decode " + W + "/img/hand_pointing_happy_0.bmp --like " + W + "/data/hand_pointing_happy_0.bvh --range " + W +
            "/img/range.json --out " + W + "/full.bvh --interp natural");
    REQUIRE_MESSAGE(r.rc == 0, r.err);
    const clip ref = read_bvh(w / "data" / "hand_pointing_happy_0.bvh");
    const clip full = read_bvh(w / "full.bvh");
    CHECK(full.frames == ref.frames);
    CHECK(full.fps == ref.fps);

    // Position channels (the forearm's translation while pushing) come from the reference, stretched in time.
    {
        const std::string stem = file_stem(hand_motion::pushing, emotion::neutral, 0);
        const clip push = read_bvh(w / "data" / (stem + ".bvh"));
        const std::size_t n = 2 * push.frames - 1;
        r = run("decode " + W + "/img/" + stem + ".bmp --like " + W + "/data/" + stem + ".bvh --range " + W +
                "/img/range.json --out " + W + "/push2.bvh --frames " + std::to_string(n));
        REQUIRE_MESSAGE(r.rc == 0, r.err);
        const clip slow = read_bvh(w / "push2.bvh");
        REQUIRE(slow.frames == n);
        double spread = 0, worst_pos = 0;
        for (std::size_t f = 0; f < push.frames; ++f)
            for (std::size_t a = 0; a < 3; ++a) {
                spread = std::max(spread, std::abs(push.position(f, 0, a) - push.position(0, 0, a)));
                worst_pos = std::max(worst_pos, std::abs(slow.position(2 * f, 0, a) - push.position(f, 0, a)));
            }
        CHECK(spread > 0.01);        // the forearm really moves
        CHECK(worst_pos < 1e-5);     // and the decoded clip follows it (BVH's 6 decimals)
    }

    // Encoding with a supplied range reproduces the same images.
    r = run("encode " + W + "/data/hand_pointing_happy_0.bvh --out " + W + "/img2 --range " + W + "/img/range.json");
    REQUIRE_MESSAGE(r.rc == 0, r.err);
    CHECK(!fs::exists(w / "img2" / "range.json"));
    CHECK(read_image(w / "img2" / "hand_pointing_happy_0.bmp") == read_image(w / "img" / "hand_pointing_happy_0.bmp"));

    // Failure cases: one line on stderr, exit 1, nothing crashes.
    expect_failure("encode " + W + "/missing.bvh --out " + W + "/x", "does not exist");
    expect_failure("decode " + W + "/missing.bmp --like " + W + "/data/hand_pointing_happy_0.bvh --range " + W +
                       "/img/range.json --out " + W + "/x.bvh",
                   "missing.bmp");
    fs::create_directories(w / "bad");
    fs::copy_file(w / "data" / "hand_crawling_sad_0.bvh", w / "bad" / "hand_crawling_bored_0.bvh");
    expect_failure("encode " + W + "/bad --out " + W + "/badimg", "bored");
    // An image of the wrong size for the range file's J x K.
    write_bmp(w / "small.bmp", rgb_image::make(22, 9));
    expect_failure("decode " + W + "/small.bmp --like " + W + "/data/hand_pointing_happy_0.bvh --range " + W +
                       "/img/range.json --out " + W + "/x.bvh",
                   "expected 23x9");
    write_bmp(w / "tall.bmp", rgb_image::make(23, 10));
    expect_failure("decode " + W + "/tall.bmp --like " + W + "/data/hand_pointing_happy_0.bvh --range " + W +
                       "/img/range.json --out " + W + "/x.bvh",
                   "23x10");
    // A range file for other keyframes, a malformed range file.
    expect_failure("encode " + W + "/data --out " + W + "/img3 --keyframes 5 --range " + W + "/img/range.json", "range.json");
    write_file_atomic(w / "broken.json", "{\"format\": \"handemo-range/1\", \"p_min\": 3}");
    expect_failure("decode " + W + "/img/hand_pointing_happy_0.bmp --like " + W + "/data/hand_pointing_happy_0.bvh --range " +
                       W + "/broken.json --out " + W + "/x.bvh",
                   "p_max");
    expect_failure("decode " + W + "/img/hand_pointing_happy_0.bmp --like " + W + "/data/hand_pointing_happy_0.bvh --range " +
                       W + "/img/range.json --out " + W + "/x.bvh --interp cubic",
                   "cubic");
    expect_failure("synth --out " + W + "/s --takes 0", "takes");
    CHECK(!fs::exists(w / "x.bvh"));
    fs::remove_all(w);
}

TEST_CASE("cli: synth --motion-set extended writes the 12-type set, the paper set's files among them unchanged")
{
    const fs::path w = work_dir() / "sets";
    fs::create_directories(w);  // the work folder again, if an earlier case removed it
    const std::string W = "'" + w.string() + "'";
    run_result r = run("synth --out " + W + "/paper --seed 4");
    REQUIRE_MESSAGE(r.rc == 0, r.err);
    r = run("synth --out " + W + "/ext --seed 4 --motion-set extended");
    REQUIRE_MESSAGE(r.rc == 0, r.err);
    std::size_t paper = 0, ext = 0;
    for (const auto& e : fs::directory_iterator(w / "paper")) paper += e.path().extension() == ".bvh";
    for (const auto& e : fs::directory_iterator(w / "ext")) ext += e.path().extension() == ".bvh";
    CHECK(paper == 35);
    CHECK(ext == 60);
    for (hand_motion m : all_hand_motions)
        for (emotion e : all_emotions) {
            const std::string f = file_stem(m, e, 0) + ".bvh";
            CHECK_MESSAGE(read_file(w / "paper" / f) == read_file(w / "ext" / f), f);
        }
    CHECK(fs::exists(w / "ext" / "hand_beckoning_fearful_0.bvh"));
    CHECK(fs::exists(w / "ext" / "hand_counting_sad_0.csv"));
    expect_failure("synth --out " + W + "/bad --motion-set all", "unknown set 'all'");
    fs::remove_all(work_dir());
}
