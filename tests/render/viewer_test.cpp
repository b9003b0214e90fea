// Tests of the HTML motion viewer (render/viewer.hpp): the page is self-contained (nothing fetched), embeds
// every clip's frame and joint count, and the embedded positions are handemo's forward kinematics.
#include "helpers.hpp"
#include "viewer_helpers.hpp"

#include <handemo/motion/bvh.hpp>
#include <handemo/render/viewer.hpp>

#include <doctest/doctest.h>

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
    CHECK(d["format"] == "handemo-view/1");
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
    for (std::size_t i = 0; i < clips.size(); ++i)
        for (const auto& p : test::viewer_expected_pixels(clips[i], i, d)) {
            CHECK(p[0] >= 480.0 * static_cast<double>(i));
            CHECK(p[0] <= 480.0 * static_cast<double>(i + 1));
            CHECK(p[1] >= viewer_title_height);
            CHECK(p[1] <= 540.0);
        }
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
}
