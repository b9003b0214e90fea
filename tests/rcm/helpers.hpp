// Hand-made motions with known feature values for the rcm tests: a planar body figure and a flat hand,
// given as point names (so the role rules find them) and [F, P, 3] positions.
#pragma once

#include <handemo/rcm.hpp>

#include <array>
#include <string>
#include <vector>

namespace rcm_test {

using handemo::vec3;

/// Point names of the body figure, in the order of body_points().
inline std::vector<std::string> body_names()
{
    return {"Head", "Neck", "Chest", "Hips", "UpperArm_L", "UpperArm_R", "LowerArm_L", "LowerArm_R", "Hand_L", "Hand_R",
            "UpperLeg_L", "UpperLeg_R", "LowerLeg_L", "LowerLeg_R", "Foot_L", "Foot_R"};
}

/// A T-pose-like figure in the x-y plane (y up, the left side at -x), facing -z; left foot pushed to z = 10
/// so that the box volumes are not zero.
inline std::vector<vec3> body_points()
{
    return {{0, 170, 0},   {0, 150, 0},  {0, 130, 0},  {0, 100, 0},  {-20, 140, 0}, {20, 140, 0}, {-45, 140, 0}, {45, 140, 0},
            {-70, 140, 0}, {70, 140, 0}, {-10, 95, 0}, {10, 95, 0},  {-10, 50, 0},  {10, 50, 0},  {-10, 0, 10},  {10, 0, 0}};
}

/// `frames` copies of points, each translated by frame * step.
inline handemo::rcm::positions_type animate(const std::vector<vec3>& pts, std::size_t frames, vec3 step = {0, 0, 0})
{
    handemo::rcm::positions_type p = xt::zeros<double>({frames, pts.size(), std::size_t{3}});
    for (std::size_t f = 0; f < frames; ++f)
        for (std::size_t q = 0; q < pts.size(); ++q)
            for (std::size_t k = 0; k < 3; ++k) p(f, q, k) = pts[q][k] + static_cast<double>(f) * step[k];
    return p;
}

/// Point names of the flat hand of hand_points().
inline std::vector<std::string> hand_names()
{
    return {"wrist", "palm", "thumb_proximal", "index_proximal", "middle_proximal", "ring_proximal", "pinky_proximal",
            "thumb_distal_end", "index_distal_end", "middle_distal_end", "ring_distal_end", "pinky_distal_end"};
}

/// A flat hand in the x-y plane: wrist at the origin, palm at y = 5, finger bases at y = 8 (x = 3, 1, -1, -3
/// for index .. pinky; thumb base at (5, 4)), every finger straight along +y by 7 (thumb tip at (5, 8, 2)), so
/// index .. pinky are parallel (spread 0).
inline std::vector<vec3> hand_points()
{
    return {{0, 0, 0}, {0, 5, 0}, {5, 4, 0},  {3, 8, 0},  {1, 8, 0},  {-1, 8, 0}, {-3, 8, 0},
            {5, 8, 2}, {3, 15, 0}, {1, 15, 0}, {-1, 15, 0}, {-3, 15, 0}};
}

}  // namespace rcm_test
