// Header-only hygiene, second translation unit (see two_tu_a.cpp).
#include <doctest/doctest.h>
#include <handemo.hpp>
#include <handemo/image.hpp>

#include <filesystem>
#include <string>

#include <unistd.h>

std::string two_tu_a_bvh(const handemo::clip& c);
handemo::rgb_image two_tu_a_roundtrip(const std::filesystem::path& p, const handemo::rgb_image& im);

TEST_CASE("two translation units including <handemo.hpp> and <handemo/image.hpp> link into one program")
{
    const handemo::clip c = handemo::parse_bvh(
        "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n}\n"
        "MOTION\nFrames: 1\nFrame Time: 0.1\n1 2 3\n",
        "two_tu.bvh");
    CHECK(two_tu_a_bvh(c) == handemo::to_bvh_string(c));
    const auto p = std::filesystem::temp_directory_path() / ("handemo_two_tu_" + std::to_string(::getpid()) + ".bmp");
    handemo::rgb_image im = handemo::rgb_image::make(2, 2);
    im.at(1, 1)[1] = 9;
    handemo::write_bmp(p, im);
    CHECK(handemo::read_image(p) == im);
    CHECK(two_tu_a_roundtrip(p, im) == im);
    std::filesystem::remove(p);
}
