// Shared by the viewer tests: the embedded JSON of a page and the pixel positions the page must draw.
#pragma once

#include <handemo/render/figure.hpp>
#include <handemo/render/viewer.hpp>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace handemo::test {

/// The JSON between <script type="application/json" id="data"> and </script>, parsed.
inline nlohmann::json viewer_data(const std::string& html)
{
    const std::string open = "<script type=\"application/json\" id=\"data\">";
    const auto a = html.find(open);
    if (a == std::string::npos) return {};
    const auto b = html.find("</script>", a);
    return nlohmann::json::parse(html.substr(a + open.size(), b - a - open.size()));
}

/// The cell of clip `ci` in CSS pixels as the page documents it (viewer.hpp viewer_title_height): row
/// ci / columns, column ci % columns, each row a title band above cells of width W / columns and height `height`.
struct viewer_cell {
    std::size_t row = 0, column = 0;
    double x = 0, y = 0, w = 0, h = 0;
};

inline viewer_cell viewer_cell_of(const nlohmann::json& d, std::size_t ci)
{
    const std::size_t cols = d["columns"];
    viewer_cell c;
    c.row = ci / cols;
    c.column = ci % cols;
    c.w = d["width"].get<double>() / static_cast<double>(cols);
    c.h = d["height"].get<double>();
    c.x = static_cast<double>(c.column) * c.w;
    c.y = static_cast<double>(c.row + 1) * viewer_title_height + static_cast<double>(c.row) * c.h;
    return c;
}

/// Pixel positions of frame `frame` of clip `ci` at the initial camera, computed from handemo's forward
/// kinematics with the projection the page documents (viewer.hpp): [points] of (x, y), joints then end sites.
/// `cell`: the cell the clip is drawn in (a V/A grid page's output), by default cell ci.
inline std::vector<std::array<double, 2>> viewer_expected_pixels(const clip& c, std::size_t ci, const nlohmann::json& d,
                                                                 std::size_t frame = 0, std::size_t cell = static_cast<std::size_t>(-1))
{
    const auto& cj = d["clips"][ci];
    const viewer_cell b = viewer_cell_of(d, cell == static_cast<std::size_t>(-1) ? ci : cell);
    const double s = viewer_fill * std::min(b.w, b.h) / (2.0 * d["radius"].get<double>());
    const vec3 right = d["view"]["right"].get<vec3>(), up = d["view"]["up"].get<vec3>(), center = cj["center"].get<vec3>();
    const pose_positions P = clip_pose(c, frame);
    std::vector<vec3> pts(P.joints.begin(), P.joints.end());
    for (std::size_t j = 0; j < P.joints.size(); ++j)
        if (detail::v_norm(detail::v_sub(P.end_sites[j], P.joints[j])) > 1e-9) pts.push_back(P.end_sites[j]);
    std::vector<std::array<double, 2>> out;
    for (const auto& p : pts) {
        const vec3 q = detail::v_sub(p, center);
        out.push_back({b.x + b.w / 2 + detail::v_dot(q, right) * s, b.y + b.h / 2 - detail::v_dot(q, up) * s});
    }
    return out;
}

}  // namespace handemo::test
