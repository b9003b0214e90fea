// The README's 10-line example, compiled and run by the tests (tests/stargan/cli_test.cmake):
//   handemo_example_transfer MODEL_DIR IN.bvh EMOTION OUT_PREFIX [left|right]
// writes OUT_PREFIX.bvh (the input transferred to EMOTION, on the input's own skeleton) and OUT_PREFIX.png (input
// and output side by side); left|right picks the hand of a body with two.
#include <handemo.hpp>
#include <handemo/image.hpp>  // PNG/BMP (target handemo::image)

#include <cstdio>
#include <string>
#include <vector>

using namespace handemo;

int main(int argc, char** argv)
try {
    if (argc != 5 && argc != 6) {
        std::fprintf(stderr, "usage: %s MODEL_DIR IN.bvh EMOTION OUT_PREFIX [left|right]\n", argv[0]);
        return 1;
    }
    const char hand = argc == 6 ? (std::string(argv[5]) == "left" ? 'l' : 'r') : 0;  // which hand of a body with two
    const std::string out = argv[4];
    // --- the README example, with its file names as arguments
    clip capture = read_bvh(argv[2]);                                 // your skeleton: SMPL-X, Mixamo, OpenXR, ...
    auto model = stargan::load_model(argv[1]);                        // the shipped model, or one `handemo train` wrote
    auto sad = stargan::transfer_capture(*model, capture, argv[3], {}, {.hand = hand});  // retarget, transfer, write back
    write_bvh(out + ".bvh", sad.motion, -1);                          // on your skeleton; other channels bit-identical
    write_png(out + ".png", render_filmstrip(std::vector{capture, sad.motion}));  // the two side by side
    // ---
    std::printf("%s -> %s: %zu frames (tempo x%.3f)%s\n", argv[2], argv[3], sad.motion.frames, sad.on_model.tempo,
                sad.retargeted ? ", retargeted" : "");
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "handemo_example_transfer: error: %s\n", e.what());
    return 1;
}
