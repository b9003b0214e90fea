// The README's 10-line example, compiled and run by the tests (tests/stargan/cli_test.cmake):
//   handemo_example_transfer MODEL_DIR IN.bvh EMOTION OUT.bvh [left|right]
// writes OUT.bvh, the input transferred to EMOTION on the input's own skeleton; left|right picks the hand of a
// body with two. It includes only the light header; examples/handemo_impl.cpp compiles its definitions once.
#include <handemo/transfer.hpp>

#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv)
try {
    if (argc != 5 && argc != 6) {
        std::fprintf(stderr, "usage: %s MODEL_DIR IN.bvh EMOTION OUT.bvh [left|right]\n", argv[0]);
        return 1;
    }
    const char hand = argc == 6 ? (std::string(argv[5]) == "left" ? 'l' : 'r') : 0;  // which hand of a body with two
    // --- the README example, with its file names as arguments
    handemo::clip capture = handemo::read_bvh(argv[2]);          // your skeleton: SMPL-X, Mixamo, OpenXR, ...
    handemo::transfer_model model(argv[1]);                       // the shipped model, or one `handemo train` wrote
    auto sad = model.transfer(capture, argv[3], {.hand = hand});  // retarget, transfer, write back
    handemo::write_bvh(argv[4], sad.motion, -1);                  // on your skeleton; other channels bit-identical
    // ---
    std::printf("%s -> %s: %zu frames (tempo x%.3f)%s\n", argv[2], argv[3], sad.motion.frames, sad.tempo,
                sad.retargeted ? ", retargeted" : "");
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "handemo_example_transfer: error: %s\n", e.what());
    return 1;
}
