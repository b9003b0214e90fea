// handemo_make_capture OUT.bvh [MOTION]: writes a capture that is not handemo's own skeleton, for the tests, the
// README and the docs: a 58-joint SMPL-X-named body with fingers (tests/retarget/rigs.hpp), standing with its right
// hand raised beside its shoulder, whose right hand performs a neutral take of one of handemo's synthetic hand motions
// (default gripping), moved onto that hand by the retargeting module, and whose body sways a little.
#include "rigs.hpp"

#include <handemo/motion.hpp>
#include <handemo/retarget.hpp>

#include <cmath>
#include <cstdio>
#include <string>

using namespace handemo;

int main(int argc, char** argv)
try {
    if (argc < 2 || argc > 3) {
        std::fprintf(stderr, "usage: %s OUT.bvh [MOTION]\n", argv[0]);
        return 2;
    }
    const hand_motion motion = hand_motion_from_string(argc > 2 ? argv[2] : "gripping");
    const clip hand = synthesize(motion, emotion::neutral, 0, 1, 30.0);
    skeleton body = test::make_rig(test::smplx_names(), test::rig_style{.a_pose_deg = 0, .name = "smplx"});
    body.name = "smplx";
    const auto b = retarget::detect(body);
    clip c = clip::make(body, hand.frames, hand.fps);
    for (std::size_t f = 0; f < c.frames; ++f) {
        const double t = static_cast<double>(f) / c.fps;
        // arms down (about the forward axis), the right forearm folded up beside the shoulder (the hand raised,
        // fingers up), a slow sway of the spine
        c.angle(f, b.at("l.upperarm"), 2) = -70;
        c.angle(f, b.at("r.upperarm"), 2) = 70;
        c.angle(f, b.at("r.forearm"), 2) = -130 + 5 * std::sin(1.3 * t);
        c.angle(f, b.at("spine"), 2) = 3 * std::sin(0.9 * t);
        c.angle(f, b.at("chest"), 0) = 2 * std::sin(0.7 * t + 1);
        c.angle(f, b.at("head"), 1) = 8 * std::sin(0.5 * t);
        for (std::size_t k = 0; k < 3; ++k) c.position(f, 0, k) = body.joints[0].offset[k];
    }
    // the synthetic hand's own motion, relative to its forearm, onto the body's right hand
    const auto m = retarget::make_map(body, hand_skeleton(), {.hand = 'r'});
    c = retarget::write_back(c, hand, m);
    c.skel.name = argv[1];
    write_bvh(argv[1], c, 4);
    std::printf("wrote %s: %zu joints (SMPL-X names), %zu frames at %g fps, right hand: neutral %s\n", argv[1], c.skel.size(), c.frames, c.fps,
                std::string(to_string(motion)).c_str());
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "handemo_make_capture: error: %s\n", e.what());
    return 1;
}
