// check_framing: the framing check of filmstrip tests (filmstrip_test.cpp, shared_data_test.cpp).
#pragma once

#include <handemo/render.hpp>

#include <doctest/doctest.h>

#include <span>

namespace handemo::test {

inline bool is_background(const rgb_image& im, long x, long y)
{
    const auto* p = im.at(static_cast<std::size_t>(y), static_cast<std::size_t>(x));
    return p[0] == 255 && p[1] == 255 && p[2] == 255;
}

/// Every joint / end site of every drawn frame lies inside its cell, at least 2 px from the border, and some
/// non-background pixel lies within 3 px of it. The border ring of each cell stays background.
inline void check_framing(std::span<const clip> clips, const filmstrip_options& opt)
{
    const rgb_image im = render_filmstrip(clips, opt);
    const filmstrip_plan plan = plan_filmstrip(clips, opt);
    const long cw = static_cast<long>(opt.cell_width), ch = static_cast<long>(opt.cell_height), g = filmstrip_gap;
    REQUIRE(opt.titles.empty());
    REQUIRE(im.width == static_cast<std::size_t>(static_cast<long>(clips.size()) * (cw + g) + g));
    REQUIRE(im.height == static_cast<std::size_t>(static_cast<long>(opt.rows) * (ch + g) + g));
    for (std::size_t c = 0; c < clips.size(); ++c) {
        for (std::size_t r = 0; r < opt.rows; ++r) {
            const long x0 = g + static_cast<long>(c) * (cw + g), y0 = g + static_cast<long>(r) * (ch + g);
            const std::size_t f = detail::filmstrip_frame(r, opt.rows, clips[c].frames);
            const pose_positions P = clip_pose(clips[c], f);
            const vec3 off = plan.track_offset(c, P, opt.figure);
            for (std::size_t j = 0; j < clips[c].skel.size(); ++j) {
                if (plan.layouts[c].hidden[j]) continue;
                if (plan.layouts[c].kind == figure_kind::hand && clips[c].skel.joints[j].parent < 0) continue;  // forearm cut
                for (const vec3& w : {P.joints[j], P.end_sites[j]}) {
                    const point2 p = plan.project(w, off);
                    CHECK(p.x >= 2);
                    CHECK(p.y >= 2);
                    CHECK(p.x <= static_cast<double>(cw) - 2);
                    CHECK(p.y <= static_cast<double>(ch) - 2);
                    bool ink = false;
                    for (long dy = -3; dy <= 3 && !ink; ++dy)
                        for (long dx = -3; dx <= 3 && !ink; ++dx) {
                            const long x = x0 + static_cast<long>(p.x) + dx, y = y0 + static_cast<long>(p.y) + dy;
                            if (x >= x0 && y >= y0 && x < x0 + cw && y < y0 + ch) ink = !is_background(im, x, y);
                        }
                    CHECK_MESSAGE(ink, "no ink near joint ", clips[c].skel.joints[j].name, " of clip ", c, " row ", r);
                }
            }
            for (long x = x0; x < x0 + cw; ++x) {  // top border row of the cell (the frame label is at the bottom)
                CHECK(is_background(im, x, y0));
            }
            for (long y = y0; y < y0 + ch; ++y) {
                CHECK(is_background(im, x0, y));
                CHECK(is_background(im, x0 + cw - 1, y));
            }
        }
    }
}

}  // namespace handemo::test
