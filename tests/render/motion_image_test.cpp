// Tests of the motion-image view (render/motion_image.hpp, the hand paper's Figure 3).
#include <handemo/motion/hand.hpp>
#include <handemo/render/motion_image.hpp>

#include <doctest/doctest.h>

#include <string>
#include <vector>

using namespace handemo;

namespace {
rgb_image gradient(std::size_t w, std::size_t h)  // pixel (r, c) = (10 r, 10 c, 7)
{
    rgb_image im = rgb_image::make(w, h);
    for (std::size_t r = 0; r < h; ++r)
        for (std::size_t c = 0; c < w; ++c) {
            im.at(r, c)[0] = static_cast<std::uint8_t>(10 * r);
            im.at(r, c)[1] = static_cast<std::uint8_t>(10 * c);
            im.at(r, c)[2] = 7;
        }
    return im;
}

/// Finds the enlarged grid: the top-left pixel of cell (0, 0) is the first pixel equal to source (0, 0)
/// scanning rows from the top; returns false when there is none.
bool find_origin(const rgb_image& view, const rgb_image& src, std::size_t& ox, std::size_t& oy)
{
    for (oy = 0; oy < view.height; ++oy)
        for (ox = 0; ox < view.width; ++ox)
            if (std::equal(view.at(oy, ox), view.at(oy, ox) + 3, src.at(0, 0))) return true;
    return false;
}
}  // namespace

TEST_CASE("motion image view: nearest-neighbour enlargement keeps every cell's colour")
{
    const rgb_image src = gradient(23, 9);
    std::vector<std::string> names;
    for (const auto& j : hand_skeleton().joints) names.push_back(j.name);
    for (std::size_t scale : {4u, 12u, 24u}) {
        const rgb_image v = render_motion_image(src, names, scale);
        v.validate("view");
        CHECK(v.width >= 23 * scale);
        CHECK(v.height >= 9 * scale);
        std::size_t ox = 0, oy = 0;
        REQUIRE(find_origin(v, src, ox, oy));
        for (std::size_t r = 0; r < 9; ++r)
            for (std::size_t c = 0; c < 23; ++c) {
                // the cell's centre pixel (grid lines are on the cell's first row/column)
                const auto* p = v.at(oy + r * scale + scale / 2, ox + c * scale + scale / 2);
                CHECK(p[0] == src.at(r, c)[0]);
                CHECK(p[1] == src.at(r, c)[1]);
                CHECK(p[2] == src.at(r, c)[2]);
            }
        if (scale >= 8) {
            // labels: ink (dark pixels) below the grid (joint names) and left of it (keyframe indices)
            bool below = false, left = false;
            for (std::size_t y = oy + 9 * scale; y < v.height; ++y)
                for (std::size_t x = 0; x < v.width; ++x) below = below || v.at(y, x)[0] < 100;
            for (std::size_t y = oy; y < oy + 9 * scale; ++y)
                for (std::size_t x = 0; x < ox; ++x) left = left || v.at(y, x)[0] < 100;
            CHECK(below);
            CHECK(left);
        } else {
            CHECK(v.width == 23 * scale);  // no room for labels
            CHECK(v.height == 9 * scale);
        }
    }
    // longer names make a taller label band
    std::vector<std::string> longer = names;
    longer[4] = "a_much_longer_joint_name_than_any_other";
    CHECK(render_motion_image(src, longer, 24).height > render_motion_image(src, names, 24).height);
}

TEST_CASE("motion image view: bad input gets a clear handemo error")
{
    const rgb_image src = gradient(23, 9);
    const std::vector<std::string> names(22, "j");
    CHECK_THROWS_WITH_AS(render_motion_image(src, names, 24), doctest::Contains("22 joint names for an image 23 columns"),
                         shape_error);
    CHECK_THROWS_AS(render_motion_image(src, {}, 0), value_error);
    CHECK_THROWS_AS(render_motion_image(src, {}, 1000), value_error);
    CHECK_THROWS_AS(render_motion_image(rgb_image{}, {}, 8), shape_error);
    rgb_image broken = src;
    broken.pixels.pop_back();
    CHECK_THROWS_AS(render_motion_image(broken, {}, 8), shape_error);
}
