// The README's 10-line example, compiled and run by the tests (tests/stargan/cli_test.cmake):
//   handemo_example_transfer MODEL_DIR IN.bvh EMOTION OUT_PREFIX
// writes OUT_PREFIX.bvh (the input transferred to EMOTION) and OUT_PREFIX.png (input and output side by side).
#include <handemo.hpp>
#include <handemo/image.hpp>  // PNG/BMP (target handemo::image)

#include <cstdio>
#include <string>
#include <vector>

using namespace handemo;

int main(int argc, char** argv)
try {
    if (argc != 5) {
        std::fprintf(stderr, "usage: %s MODEL_DIR IN.bvh EMOTION OUT_PREFIX\n", argv[0]);
        return 1;
    }
    const std::string out = argv[4];
    // --- the README example, with its file names as arguments
    clip walk = read_bvh(argv[2]);                                    // any skeleton, any channel order
    auto model = stargan::load_model(argv[1]);                        // written by `handemo train`
    auto sad = model->transfer(walk, argv[3]);                        // keyframes -> Eq.3 -> G -> Eq.6 -> spline
    write_bvh(out + ".bvh", sad.motion);                              // tempo and amplitude learned from the data
    write_png(out + ".png", render_filmstrip(std::vector{walk, sad.motion}));  // the two side by side
    // ---
    std::printf("%s -> %s: %zu frames (tempo x%.3f)\n", argv[2], argv[3], sad.motion.frames, sad.tempo);
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "handemo_example_transfer: error: %s\n", e.what());
    return 1;
}
