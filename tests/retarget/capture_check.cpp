// test_retarget_capture IN.bvh OUT.bvh HAND: checks a transfer of a capture's hand written back by the CLI
// (tests/retarget/cli_test.cmake): the output reads back with read_bvh, keeps the capture's joint names,
// hierarchy, channel order, offsets and frame rate; every channel of every joint outside that hand's wrist and
// fingers is bit-identical to the capture resampled to the output's length; the hand's channels did change.
#include <handemo/motion.hpp>
#include <handemo/retarget.hpp>

#include <cstdio>
#include <cstring>
#include <string>

using namespace handemo;

int main(int argc, char** argv)
try {
    if (argc != 4) {
        std::fprintf(stderr, "usage: %s IN.bvh OUT.bvh left|right\n", argv[0]);
        return 2;
    }
    const clip in = read_bvh(argv[1]), out = read_bvh(argv[2]);
    const char side = std::string(argv[3]) == "left" ? 'l' : 'r';
    int bad = 0;
    auto fail = [&](const std::string& m) {
        std::fprintf(stderr, "FAIL: %s\n", m.c_str());
        ++bad;
    };
    if (out.skel.size() != in.skel.size()) fail("joint count changed");
    for (std::size_t j = 0; j < in.skel.size() && j < out.skel.size(); ++j) {
        const auto &a = in.skel.joints[j], &b = out.skel.joints[j];
        if (a.name != b.name || a.parent != b.parent || a.channels != b.channels || a.offset != b.offset || a.end_site != b.end_site)
            fail("joint " + a.name + ": name, parent, channels, offset or End Site changed");
    }
    if (out.fps != in.fps) fail("frame rate changed");
    if (bad) return 1;
    // the hand's joints: the side's wrist and every joint below it
    const auto b = retarget::detect(in.skel);
    const std::size_t wrist = b.at(std::string(1, side) + ".hand");
    std::vector<bool> hand(in.skel.size(), false);
    hand[wrist] = true;
    for (std::size_t j = wrist + 1; j < in.skel.size(); ++j)
        if (in.skel.joints[j].parent >= 0 && hand[static_cast<std::size_t>(in.skel.joints[j].parent)]) hand[j] = true;
    const clip ref = retarget::resample(in, out.frames);
    std::size_t same = 0, changed = 0;
    for (std::size_t j = 0; j < in.skel.size(); ++j)
        for (std::size_t f = 0; f < out.frames; ++f)
            for (std::size_t c = 0; c < 3; ++c) {
                const double a = out.angle(f, j, c), r = ref.angle(f, j, c);
                if (std::memcmp(&out.positions[(f * in.skel.size() + j) * 3 + c], &ref.positions[(f * in.skel.size() + j) * 3 + c], sizeof(double)))
                    fail("position channel of " + in.skel.joints[j].name + " changed at frame " + std::to_string(f));
                if (!hand[j]) {
                    if (std::memcmp(&a, &r, sizeof a)) fail("rotation of " + in.skel.joints[j].name + " changed at frame " + std::to_string(f));
                    else ++same;
                } else {
                    changed += a != r;
                }
            }
    if (changed == 0) fail("the hand did not change");
    std::printf("capture check: %zu frames (capture %zu), %zu channel values outside the hand bit-identical, %zu hand values changed, %d failures\n",
                out.frames, in.frames, same, changed, bad);
    return bad ? 1 : 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "test_retarget_capture: error: %s\n", e.what());
    return 1;
}
