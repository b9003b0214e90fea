// Helpers shared by the format test programs (bvh_test, shared_data_test).
#pragma once

#include <doctest/doctest.h>
#include <handemo/motion/skeleton.hpp>

#include <cmath>
#include <cstddef>

namespace handemo::test {

/// Same topology, channels, offsets and End Sites within `tol`.
inline void check_same_skeleton(const skeleton& a, const skeleton& b, double tol)
{
    REQUIRE(a.same_topology(b));
    for (std::size_t j = 0; j < a.size(); ++j) {
        CHECK(a.joints[j].channels == b.joints[j].channels);
        for (std::size_t k = 0; k < 3; ++k) CHECK(std::abs(a.joints[j].offset[k] - b.joints[j].offset[k]) <= tol);
        REQUIRE(a.joints[j].end_site.has_value() == b.joints[j].end_site.has_value());
        if (a.joints[j].end_site)
            for (std::size_t k = 0; k < 3; ++k)
                CHECK(std::abs((*a.joints[j].end_site)[k] - (*b.joints[j].end_site)[k]) <= tol);
    }
}

}  // namespace handemo::test
