// Filmstrips of real Bandai BVH clips (../shared/data, label shared-data: without the data
// `--shared-data` exits 77 and is reported as skipped, see tests/test_main.cpp).
#include "framing.hpp"

#include <handemo/motion/bvh.hpp>
#include <handemo/render.hpp>

#include <doctest/doctest.h>

#include <filesystem>
#include <vector>

// run by `<program> --shared-data` only (tests/test_main.cpp)
TEST_SUITE_BEGIN("shared-data");

using namespace handemo;
using handemo::test::check_framing;

TEST_CASE("filmstrip: real Bandai clips")
{
    const std::filesystem::path dir = std::filesystem::path(HANDEMO_SHARED_DIR) / "data" / "bandai";
    const auto a = dir / "dataset-1_walk_normal_001.bvh", b = dir / "dataset-1_walk_sad_001.bvh";
    const std::vector<clip> clips{read_bvh(a), read_bvh(b)};
    const figure_layout L = analyse_figure(clips[0].skel);
    CHECK(L.kind == figure_kind::body);
    CHECK(L.hidden[0] == 1);           // joint_Root
    CHECK(L.limb_heads.size() == 5);   // head, two arms, two legs
    filmstrip_options opt;
    opt.rows = 3;
    opt.cell_width = 100;
    opt.cell_height = 160;
    check_framing(clips, opt);
}

TEST_SUITE_END();
