#include <handemo/image/keyframe_image.hpp>
#include <handemo/motion/synth.hpp>

#include <doctest/doctest.h>

#include <filesystem>

using namespace handemo;

TEST_CASE("keyframe_image: keyframes -> BMP/PNG -> keyframes is lossless on pixels; wrong sizes are refused")
{
    namespace fs = std::filesystem;
    const fs::path dir = fs::temp_directory_path() / ("handemo_codec_image_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const clip c = synthesize(hand_motion::pointing, emotion::angry, 0, 5);
    const auto kf = extract_keyframes<9>(c);
    const angle_range r = compute_range(std::vector<keyframes<9>>{kf});
    const auto px = encode(kf, r);
    const rgb_image im = to_image(px);
    CHECK(im.width == 23);
    CHECK(im.height == 9);
    // Pixel (row i, column j) holds keyframe i, joint j.
    CHECK(im.at(4, 7)[2] == px.at(4, 7, 2));
    write_bmp(dir / "a.bmp", im);
    write_png(dir / "a.png", im);
    for (const char* name : {"a.bmp", "a.png"}) {
        const auto back = from_image<9>(read_image(dir / name), r, name);
        CHECK(back.values == px.values);
        const auto kb = decode(back, r);
        for (std::size_t i = 0; i < kb.angles.size(); ++i)
            CHECK(std::abs(kb.angles[i] - kf.angles[i]) <= r.max_roundtrip_error() + 1e-12);
    }
    const auto dyn = from_image<dynamic_keyframes>(im, 23, 9);
    CHECK(dyn.count() == 9);
    try {
        (void)from_image<9>(im, angle_range{0, 1, 9, 22}, "a.bmp");
        FAIL("no error");
    } catch (const shape_error& e) {
        const std::string w = e.what();
        CHECK_MESSAGE(w.find("a.bmp") != std::string::npos, w);
        CHECK_MESSAGE(w.find("23x9") != std::string::npos, w);
        CHECK_MESSAGE(w.find("22x9") != std::string::npos, w);
    }
    CHECK_THROWS_AS(from_image<9>(im, 23, 8), shape_error);
    CHECK_THROWS_AS(from_image<dynamic_keyframes>(im, angle_range{0, 1, 0, 0}), value_error);
    fs::remove_all(dir);
}
