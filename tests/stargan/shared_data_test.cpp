// StarGAN cases that read ../shared/data (label shared-data: without the data this program exits 77 and is
// reported as skipped, see tests/shared_data_main.cpp): transfer refuses a body clip (Xia) for a hand model,
// and a body's root translation (Bandai walk) is stretched in time. Moved unchanged from train_test.cpp.
#include <doctest/doctest.h>
#include <handemo/motion/synth.hpp>
#include <handemo/stargan.hpp>

#include <cmath>
#include <filesystem>

namespace fs = std::filesystem;
using namespace handemo;
using namespace handemo::stargan;

namespace {

/// A toy set: 3 motion types x 5 emotions x 1 take of the synthetic hand data, as labelled clips.
std::vector<labelled_clip> toy_set()
{
    std::vector<labelled_clip> out;
    for (auto& it : synthesize_dataset(1, 7)) {
        if (it.motion != hand_motion::gripping && it.motion != hand_motion::patting && it.motion != hand_motion::pointing)
            continue;
        labelled_clip c;
        c.path = it.file_stem + ".bvh";
        const auto n = parse_clip_name(it.file_stem);
        c.content = n.content;
        c.emotion = n.emotion;
        c.take = n.take;
        c.motion = it.c;
        out.push_back(std::move(c));
    }
    return out;
}

config_info tiny_info() { return make_info<hand_tiny>("hand-tiny", hand_domains(), "neutral"); }

train_options quiet(long iters)
{
    train_options o;
    o.iters = iters;
    o.threads = 2;
    o.checkpoint_every = 1000;
    o.log_every = 1;
    o.progress_out = nullptr;
    o.seed = 11;
    return o;
}

fs::path fresh_dir(const char* name)
{
    const fs::path d = fs::temp_directory_path() / name;
    fs::remove_all(d);
    return d;
}

}  // namespace

TEST_CASE("transfer: shapes, durations from the tempo factors, skeleton and emotion checks")
{
    const auto clips = toy_set();
    const fs::path d = fresh_dir("handemo_train_transfer");
    trainer<hand_tiny> tr(tiny_info(), prepare_data<hand_tiny>(clips, tiny_info()), quiet(10));
    tr.run(d);
    const auto model = load_model(d);
    CHECK(model->info().config == "hand-tiny");
    const clip& in = clips[2].motion;  // gripping neutral
    REQUIRE(clips[2].emotion == "neutral");
    for (const char* e : {"angry", "sad", "neutral"}) {
        const auto r = model->transfer(in, e);
        CHECK(r.motion.skel.size() == 23);
        CHECK(r.motion.fps == in.fps);
        CHECK(r.image.count() == 9);
        CHECK(r.image.joints == 23);
        const double expect = std::round(double(in.frames) * tr.data().tempo[domain_index(tiny_info(), e)]);
        CHECK(double(r.motion.frames) == expect);
        r.motion.validate("out");
    }
    CHECK(model->transfer(in, "sad").motion.frames > in.frames);
    CHECK(model->transfer(in, "angry").motion.frames < in.frames);
    CHECK_THROWS_WITH_AS(model->transfer(in, "bored"), doctest::Contains("bored"), value_error);
    const clip body = read_bvh(fs::path(HANDEMO_SHARED_DIR) / "data" / "xia" / "neutral_16_000.bvh");
    CHECK_THROWS_WITH_AS(model->transfer(body, "sad"), doctest::Contains("wrong skeleton"), shape_error);
}

TEST_CASE("transfer keeps a body's root translation and stretches it in time")
{
    const clip walk = read_bvh(fs::path(HANDEMO_SHARED_DIR) / "data" / "bandai" / "dataset-1_walk_normal_001.bvh");
    const std::size_t n = 2 * walk.frames - 1, J3 = walk.skel.size() * 3;  // twice as slow
    const auto pos = stretch_positions(walk, n);
    REQUIRE(pos.size() == n * J3);
    // frame 2k of the output is frame k of the input; odd frames lie halfway between their neighbours
    for (std::size_t k = 0; k < walk.frames; ++k)
        for (std::size_t i = 0; i < J3; ++i) REQUIRE(pos[2 * k * J3 + i] == doctest::Approx(walk.positions[k * J3 + i]));
    const std::size_t hips = walk.skel.index_of("Hips");
    for (std::size_t k = 0; k + 1 < walk.frames; ++k)
        REQUIRE(pos[(2 * k + 1) * J3 + hips * 3 + 2] ==
                doctest::Approx(0.5 * (walk.position(k, hips, 2) + walk.position(k + 1, hips, 2))));
}
