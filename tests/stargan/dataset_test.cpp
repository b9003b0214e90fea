#include <doctest/doctest.h>
#include <handemo/stargan/dataset.hpp>

#include <filesystem>

namespace fs = std::filesystem;
using namespace handemo;

TEST_CASE("parse_clip_name takes the last three fields")
{
    auto n = stargan::parse_clip_name("hand_hand-on-mouse_angry_3");
    CHECK(n.prefix == "hand");
    CHECK(n.content == "hand-on-mouse");
    CHECK(n.emotion == "angry");
    CHECK(n.take == "3");
    n = stargan::parse_clip_name("dataset-1_walk-back_not-confident_001");
    CHECK(n.prefix == "dataset-1");
    CHECK(n.content == "walk-back");
    CHECK(n.emotion == "not-confident");
    n = stargan::parse_clip_name("my_prefix_x_walk_sad_2");
    CHECK(n.prefix == "my_prefix_x");
    CHECK_THROWS_WITH_AS(stargan::parse_clip_name("walk_sad"), doctest::Contains("walk_sad"), value_error);
    CHECK_THROWS_AS(stargan::parse_clip_name("a__sad_1"), value_error);
}

TEST_CASE("load_folder reads the Bandai clips with labels from names and leaves a content out")
{
    const fs::path dir = fs::path(HANDEMO_SHARED_DIR) / "data" / "bandai";
    REQUIRE(fs::is_directory(dir));
    stargan::load_options opt;
    opt.exclude_contents = {"walk", "run", "dash", "walk-back", "walk-left"};
    const auto d = stargan::load_folder(dir, opt);
    CHECK(d.size() == 16);  // bow and bye x 8 styles
    for (const auto& c : d) {
        CHECK((c.content == "bow" || c.content == "bye"));
        CHECK(c.motion.skel.size() == 22);
    }
    const auto contents = stargan::contents_of(d);
    CHECK(contents == std::vector<std::string>{"bow", "bye"});
}

TEST_CASE("manifest.csv labels clips and bad manifests are refused with the line")
{
    const fs::path dir = fs::temp_directory_path() / "handemo_manifest_test";
    fs::remove_all(dir);
    fs::create_directories(dir);
    clip c = clip::make(hand_skeleton(), 10, 30);
    write_bvh(dir / "a.bvh", c);
    c = clip::make(hand_skeleton(), 20, 30);
    write_bvh(dir / "b.bvh", c);
    write_file_atomic(dir / "manifest.csv", "path,content,emotion\na.bvh,wave,neutral\nb.bvh,wave,sad\n");
    auto d = stargan::load_folder(dir);
    REQUIRE(d.size() == 2);
    CHECK(d[0].emotion == "neutral");
    CHECK(d[1].emotion == "sad");
    const auto tempo = stargan::tempo_factors(d, {"neutral", "sad", "happy"}, "neutral");
    CHECK(tempo[0] == doctest::Approx(1.0));
    CHECK(tempo[1] == doctest::Approx(2.0));
    CHECK(tempo[2] == doctest::Approx(1.0));  // no data: unchanged
    write_file_atomic(dir / "manifest.csv", "path,content,emotion\na.bvh,wave\n");
    CHECK_THROWS_WITH_AS(stargan::load_folder(dir), doctest::Contains("manifest.csv:2"), format_error);
    fs::remove_all(dir);
}

TEST_CASE("load_folder refuses a folder whose clips have different skeletons")
{
    const fs::path dir = fs::temp_directory_path() / "handemo_mixed_skel_test";
    fs::remove_all(dir);
    fs::create_directories(dir);
    write_bvh(dir / "h_wave_neutral_0.bvh", clip::make(hand_skeleton(), 10, 30));
    fs::copy_file(fs::path(HANDEMO_SHARED_DIR) / "data" / "xia" / "neutral_16_000.bvh", dir / "h_wave_sad_0.bvh");
    CHECK_THROWS_AS(stargan::load_folder(dir), shape_error);
    fs::remove_all(dir);
}
