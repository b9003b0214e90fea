// Compares the differentiable features (features_ad.hpp) with the analysis side's double-precision
// definitions (lma.hpp's basic_table) on every frame of a clip.
#pragma once

#include "helpers.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <string>
#include <vector>

namespace handemo::test {

/// Checks every keyed feature on every frame; returns how many keys were compared.
inline std::size_t check_against_lma(const clip& c, double rel = 1e-9)
{
    const rcm::positions_type pos = rcm::world_positions(c);
    const rcm::role_map roles = rcm::find_roles(c.skel);
    const rcm::feature_set fs = rcm::detect_feature_set(roles);
    const auto table = rcm::basic_table(pos, c.fps, roles, fs);
    const rcm::rig r = rcm::make_rig(c.skel, roles);
    const std::size_t F = c.frames;
    std::vector<std::vector<double>> pts(r.points.size(), std::vector<double>(F * 3));
    double ground = 1e300;
    for (std::size_t f = 0; f < F; ++f) {
        for (std::size_t q = 0; q < r.points.size(); ++q)
            for (std::size_t a = 0; a < 3; ++a) pts[q][f * 3 + a] = pos(f, r.point_index[q], a);
        for (std::size_t p = 0; p < pos.shape()[1]; ++p) ground = std::min(ground, pos(f, p, 1));
    }
    std::vector<double> times(F);
    for (std::size_t f = 0; f < F; ++f) times[f] = static_cast<double>(f) / c.fps;
    std::vector<std::string> names, keys;
    const auto mine = rcm::feature_values(r, times, ground, pts, 1.0, &names, &keys);
    std::size_t compared = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        if (keys[i].empty()) continue;
        const std::size_t col = static_cast<std::size_t>(std::stoi(keys[i].substr(1))) - 1;
        REQUIRE(col < table.shape()[1]);
        double worst = 0;
        for (std::size_t f = 0; f < F; ++f) {
            const double a = mine[i][f], b = table(f, col);
            worst = std::max(worst, std::abs(a - b) / (1.0 + std::abs(b)));
        }
        INFO(keys[i] << " (" << names[i] << ") worst relative difference " << worst);
        CHECK(worst <= rel);
        ++compared;
    }
    return compared;
}

}  // namespace handemo::test
