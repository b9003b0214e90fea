// Tests of the HTML motion viewer (render/viewer.hpp): the page is self-contained (nothing fetched), embeds
// every clip's frame and joint count, the embedded positions are handemo's forward kinematics, and the clips
// are laid out in a grid of the documented cells.
#include "helpers.hpp"
#include "viewer_helpers.hpp"

#include <handemo/motion/bvh.hpp>
#include <handemo/render/viewer.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <iterator>
#include <string>
#include <vector>

using namespace handemo;

TEST_CASE("viewer: the page is self-contained and embeds every clip")
{
    const std::vector<clip> clips{test::flexing_hand(40), test::flexing_hand(25), test::stick_body(30)};
    viewer_options o;
    o.titles = {"neutral", "angry </script><b>", "body"};
    const std::string html = render_viewer_html(clips, o);
    for (const char* bad : {"http://", "https://", "src=", "<link", "@import", "url(", "fetch(", "XMLHttpRequest", "//cdn"})
        CHECK_MESSAGE(html.find(bad) == std::string::npos, bad);
    CHECK(html.find("<canvas") != std::string::npos);
    CHECK(html.find("</script><b>") == std::string::npos);  // a title cannot close the data block
    const auto d = test::viewer_data(html);
    REQUIRE(d.is_object());
    CHECK(d["format"] == "handemo-view/2");
    CHECK(d["columns"] == 3);
    REQUIRE(d["clips"].size() == clips.size());
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const auto& c = d["clips"][i];
        CHECK(c["frames"] == clips[i].frames);
        CHECK(c["joints"] == clips[i].joint_count());
        CHECK(c["title"] == o.titles[i]);
        const std::size_t np = c["points"];
        CHECK(c["positions"].size() == clips[i].frames * np * 3);
        CHECK(c["parents"].size() == np);
        CHECK(c["names"].size() == np);
        CHECK(c["colors"].size() == np);
    }
    CHECK(d["normalised"] == false);
    o.normalised_time = true;
    CHECK(test::viewer_data(render_viewer_html(clips, o))["normalised"] == true);
}

TEST_CASE("viewer: embedded positions are handemo's forward kinematics, colours are the filmstrip's")
{
    const std::vector<clip> clips{test::flexing_hand(40), read_bvh(std::string(HANDEMO_SOURCE_DIR) + "/tests/render/data/arm.bvh")};
    const auto d = test::viewer_data(render_viewer_html(clips));
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const clip& c = clips[i];
        const auto& cj = d["clips"][i];
        const std::size_t np = cj["points"], J = c.joint_count();
        const auto pos = cj["positions"].get<std::vector<double>>();
        const figure_layout L = analyse_figure(c.skel);
        for (std::size_t f : {std::size_t{0}, c.frames / 2, c.frames - 1}) {
            const pose_positions P = clip_pose(c, f);
            std::size_t e = J;
            for (std::size_t j = 0; j < J; ++j) {
                for (std::size_t k = 0; k < 3; ++k)
                    CHECK(pos[(f * np + j) * 3 + k] == doctest::Approx(P.joints[j][k]).epsilon(1e-6).scale(1.0));
                if (detail::v_norm(detail::v_sub(P.end_sites[j], P.joints[j])) > 1e-9) {
                    for (std::size_t k = 0; k < 3; ++k)
                        CHECK(pos[(f * np + e) * 3 + k] == doctest::Approx(P.end_sites[j][k]).epsilon(1e-6).scale(1.0));
                    CHECK(cj["parents"][e] == j);
                    ++e;
                }
            }
            CHECK(e == np);
        }
        for (std::size_t j = 0; j < J; ++j) {
            CHECK(cj["parents"][j] == c.skel.joints[j].parent);
            CHECK(cj["names"][j] == c.skel.joints[j].name);
            CHECK(cj["colors"][j] == detail::hex_color(L.color_of(j)));
        }
    }
    // the hand's index finger is the filmstrip's orange
    const auto& h = d["clips"][0];
    for (std::size_t j = 0; j < clips[0].joint_count(); ++j)
        if (clips[0].skel.joints[j].name.find("index") != std::string::npos) CHECK(h["colors"][j] == "#f0961e");
}

TEST_CASE("viewer: the C++ projection of frame 0 stays inside each clip's cell")
{
    const std::vector<clip> clips{test::flexing_hand(10), test::stick_body(10)};
    const auto d = test::viewer_data(render_viewer_html(clips));
    CHECK(d["columns"] == 2);
    for (std::size_t i = 0; i < clips.size(); ++i)
        for (const auto& p : test::viewer_expected_pixels(clips[i], i, d)) {
            CHECK(p[0] >= 480.0 * static_cast<double>(i));
            CHECK(p[0] <= 480.0 * static_cast<double>(i + 1));
            CHECK(p[1] >= viewer_title_height);
            CHECK(p[1] <= viewer_title_height + 540.0);
        }
}

namespace {

/// Ten clips, hands and bodies alternating.
std::vector<clip> ten_clips()
{
    std::vector<clip> c;
    for (std::size_t i = 0; i < 10; ++i) c.push_back(i % 2 ? test::stick_body(12) : test::flexing_hand(12));
    return c;
}

}  // namespace

TEST_CASE("viewer: 10 clips in 5 columns put clip 7 in row 1, column 2, its figure inside that cell")
{
    const auto clips = ten_clips();
    viewer_options o;
    o.columns = 5;
    o.width = 1000;
    o.height = 300;
    const auto d = test::viewer_data(render_viewer_html(clips, o));
    REQUIRE(d["columns"] == 5);
    CHECK(d["width"] == 1000);
    CHECK(d["height"] == 300);
    const test::viewer_cell c7 = test::viewer_cell_of(d, 7);
    CHECK(c7.row == 1);
    CHECK(c7.column == 2);
    // 200 x 300 cells; row 1 starts below row 0's title band and cells and its own title band
    CHECK(c7.x == doctest::Approx(400));
    CHECK(c7.w == doctest::Approx(200));
    CHECK(c7.y == doctest::Approx(2 * viewer_title_height + 300));
    CHECK(c7.h == doctest::Approx(300));
    for (std::size_t f : {std::size_t{0}, std::size_t{6}, std::size_t{11}}) {
        double lo_x = 1e9, hi_x = -1e9, lo_y = 1e9, hi_y = -1e9;
        for (const auto& p : test::viewer_expected_pixels(clips[7], 7, d, f)) {
            CHECK(p[0] >= 400.0);
            CHECK(p[0] <= 600.0);
            CHECK(p[1] >= 2 * viewer_title_height + 300.0);
            CHECK(p[1] <= 2 * (viewer_title_height + 300.0));
            lo_x = std::min(lo_x, p[0]), hi_x = std::max(hi_x, p[0]), lo_y = std::min(lo_y, p[1]), hi_y = std::max(hi_y, p[1]);
        }
        // the figure fills its panel: the shared scale is set by the cell's narrower side (200 px), and the body
        // reaches well over half of it
        CHECK(std::max(hi_x - lo_x, hi_y - lo_y) > 100.0);
    }
    // every clip inside its own cell, row by row
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const double x0 = 200.0 * static_cast<double>(i % 5), y0 = static_cast<double>(i / 5 + 1) * viewer_title_height + 300.0 * static_cast<double>(i / 5);
        for (const auto& p : test::viewer_expected_pixels(clips[i], i, d)) {
            CHECK(p[0] >= x0);
            CHECK(p[0] <= x0 + 200.0);
            CHECK(p[1] >= y0);
            CHECK(p[1] <= y0 + 300.0);
        }
    }
}

TEST_CASE("viewer: automatic columns put at most 5 clips in a row, the rows filled evenly")
{
    // n clips -> columns: ceil(n / rows), rows = ceil(n / 5)
    const std::size_t want[] = {0, 1, 2, 3, 4, 5, 3, 4, 4, 5, 5, 4, 4, 5, 5, 5, 4};
    for (std::size_t n = 1; n < std::size(want); ++n) CHECK_MESSAGE(viewer_columns(n, 0) == want[n], n, " clips");
    CHECK(viewer_columns(10, 3) == 3);
    CHECK(viewer_columns(3, 7) == 3);  // more columns than clips: one row
    CHECK(viewer_columns(3, 10000) == 3);

    // 10 clips: 2 rows of 5, the same page as asking for 5 columns
    const auto clips = ten_clips();
    const std::string automatic = render_viewer_html(clips);
    const auto d = test::viewer_data(automatic);
    REQUIRE(d["columns"] == 5);
    for (std::size_t i = 0; i < clips.size(); ++i) {
        const test::viewer_cell c = test::viewer_cell_of(d, i);
        CHECK(c.row == i / 5);
        CHECK(c.column == i % 5);
    }
    viewer_options o;
    o.columns = 5;
    CHECK(render_viewer_html(clips, o) == automatic);
    o.columns = 40;  // clamped to the clip count: one row of 10
    CHECK(test::viewer_data(render_viewer_html(clips, o))["columns"] == 10);
}

TEST_CASE("viewer: bad input is refused")
{
    CHECK_THROWS_AS(render_viewer_html(std::vector<clip>{}), value_error);
    viewer_options o;
    o.titles = {"a", "b"};
    CHECK_THROWS_WITH_AS(render_viewer_html(std::vector<clip>{test::flexing_hand(5)}, o), doctest::Contains("2 titles for 1 clips"),
                         value_error);
    clip empty = test::flexing_hand(5);
    empty.frames = 0;
    empty.angles.clear();
    empty.positions.clear();
    CHECK_THROWS_WITH_AS(render_viewer_html(std::vector<clip>{empty}), doctest::Contains("0 frames"), value_error);

    const std::vector<clip> one{test::flexing_hand(5)};
    viewer_options g;
    g.columns = 10001;
    CHECK_THROWS_WITH_AS(render_viewer_html(one, g), doctest::Contains("columns 10001 is not in 0..10000"), value_error);
    g.columns = 0;
    g.height = 20000;
    CHECK_THROWS_WITH_AS(render_viewer_html(one, g), doctest::Contains("cell height 20000 is not in 64..16384"), value_error);
    // 40 rows of 400 + 24 pixels would make a canvas no browser draws
    g.columns = 1;
    g.height = 400;
    CHECK_THROWS_WITH_AS(render_viewer_html(std::vector<clip>(40, test::flexing_hand(2)), g), doctest::Contains("16960 pixels tall"), value_error);
    CHECK_NOTHROW(render_viewer_html(std::vector<clip>(38, test::flexing_hand(2)), g));  // 38 (24 + 400) = 16112
}

TEST_CASE("va_grid: the points of an n x n grid over [-1, 1]^2 that lie in the unit disc, row by row from the lowest arousal")
{
    using P = std::pair<double, double>;
    CHECK(va_grid(3) == std::vector<P>{{0, -1}, {-1, 0}, {0, 0}, {1, 0}, {0, 1}});
    const auto g5 = va_grid(5);
    CHECK(g5.size() == 13);  // arousal +-1: 1 point each, +-0.5: 3 each, 0: 5
    CHECK(g5.front() == P{0, -1});
    CHECK(g5[6] == P{0, 0});
    CHECK(g5.back() == P{0, 1});
    const auto g4 = va_grid(4);  // no centre, no axis: the four points (+-1/3, +-1/3)
    REQUIRE(g4.size() == 4);
    CHECK(g4[0].first == doctest::Approx(-1.0 / 3));
    CHECK(g4[3].second == doctest::Approx(1.0 / 3));
    for (const auto& [v, a] : va_grid(21)) CHECK(v * v + a * a <= 1.0 + 1e-12);
    CHECK_THROWS_AS(va_grid(2), value_error);
    CHECK_THROWS_AS(va_grid(102), value_error);
    CHECK(nearest_va_point(g5, 0.3, -0.2) == 7);   // (0.5, 0)
    CHECK(nearest_va_point(g5, -0.1, 0.4) == 10);  // (0, 0.5)
}

TEST_CASE("viewer: a page with a V/A grid embeds the grid's points and labels and lays out the shown cells")
{
    const auto points = va_grid(3);
    std::vector<clip> clips{test::stick_body(20)};  // the input, then one output per point
    for (std::size_t k = 0; k < points.size(); ++k) clips.push_back(test::flexing_hand(10 + k));
    viewer_options o;
    o.va_grid = viewer_va_grid{1, 3, points, {{"neutral", 0.1, -0.2}, {"angry", -0.6, 0.7}}};
    const std::string html = render_viewer_html(clips, o);
    const auto d = test::viewer_data(html);
    REQUIRE(d.contains("grid"));
    CHECK(d["grid"]["first"] == 1);
    CHECK(d["grid"]["n"] == 3);
    REQUIRE(d["grid"]["points"].size() == points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
        CHECK(d["grid"]["points"][k][0].get<double>() == points[k].first);
        CHECK(d["grid"]["points"][k][1].get<double>() == points[k].second);
        CHECK(d["clips"][k + 1]["frames"] == 10 + k);  // clip first + k is the output at point k
    }
    CHECK(d["grid"]["labels"][1][0] == "angry");
    CHECK(d["grid"]["labels"][1][2].get<double>() == 0.7);
    CHECK(d["columns"] == 2);  // two cells shown: the input and the picked output
    CHECK(d["clips"].size() == clips.size());
    CHECK(html.find("@HANDEMO_") == std::string::npos);
    CHECK(html.find("id=\"dial\"") != std::string::npos);
    CHECK_FALSE(test::viewer_data(render_viewer_html(std::vector<clip>(clips.begin(), clips.begin() + 2))).contains("grid"));
    // a point count other than the grid's clips, a point outside the disc, a label outside it
    auto bad = o;
    bad.va_grid->points.pop_back();
    CHECK_THROWS_WITH_AS(render_viewer_html(clips, bad), doctest::Contains("one clip per grid point"), value_error);
    bad = o;
    bad.va_grid->points[0] = {0.9, 0.9};
    CHECK_THROWS_WITH_AS(render_viewer_html(clips, bad), doctest::Contains("outside the circumplex"), value_error);
    bad = o;
    bad.va_grid->labels[1].valence = 2;
    CHECK_THROWS_WITH_AS(render_viewer_html(clips, bad), doctest::Contains("label 'angry'"), value_error);
}
