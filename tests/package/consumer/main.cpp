// Consumer smoke test: builds a clip, round-trips it through BVH text, writes and reads back a BMP, makes the
// offline viewer page (whose page text is the header CMake generates at build time and installs), and (when
// handemo::gif exists) writes the clip as an animated GIF. It includes the modules it uses, as a program that
// does not train should (the umbrella <handemo.hpp> is compiled by the project's own tests).
#include <handemo/image.hpp>
#include <handemo/motion.hpp>
#include <handemo/render.hpp>
#ifdef HANDEMO_CONSUMER_GIF
#include <handemo/gif.hpp>
#endif

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

int main(int argc, char** argv)
{
    handemo::skeleton sk;
    sk.joints.resize(2);
    sk.joints[0].name = "root";
    sk.joints[0].channels = {handemo::channel::xposition, handemo::channel::yposition, handemo::channel::zposition,
                             handemo::channel::zrotation, handemo::channel::xrotation, handemo::channel::yrotation};
    sk.joints[1].name = "tip";
    sk.joints[1].parent = 0;
    sk.joints[1].offset = {0, 1, 0};
    handemo::clip c = handemo::clip::make(sk, 3, 30);
    c.angle(2, 1, 0) = 45.5;
    const handemo::clip r = handemo::parse_bvh(handemo::to_bvh_string(c), "consumer.bvh");
    if (r.frames != 3 || r.angle(2, 1, 0) != 45.5) {
        std::puts("consumer: BVH round trip failed");
        return 1;
    }
    handemo::rgb_image im = handemo::rgb_image::make(23, 9);
    im.at(8, 22)[2] = 255;
    const std::filesystem::path p = std::filesystem::path(argc > 1 ? argv[1] : ".") / "consumer.bmp";
    handemo::write_bmp(p, im);
    if (!(handemo::read_image(p, 23, 9) == im)) {
        std::puts("consumer: BMP round trip failed");
        return 1;
    }
    const std::vector<handemo::clip> one{c};
    const std::string page = handemo::render_viewer_html(one);
    if (page.find("<!DOCTYPE html>") != 0 || page.find("handemo-view/2") == std::string::npos || page.find("@HANDEMO_") != std::string::npos) {
        std::puts("consumer: viewer page incomplete");
        return 1;
    }
#ifdef HANDEMO_CONSUMER_GIF
    handemo::animation_options ao;
    ao.strip.cell_width = ao.strip.cell_height = 32;
    const std::vector<handemo::clip> clips{c};
    if (handemo::write_gif(std::filesystem::path(argc > 1 ? argv[1] : ".") / "consumer.gif", handemo::filmstrip_animation(clips, ao)) == 0) {
        std::puts("consumer: GIF write failed");
        return 1;
    }
#endif
    std::puts("consumer: ok");
    return 0;
}
