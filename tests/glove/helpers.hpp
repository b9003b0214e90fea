// Shared helpers of the glove tests: the shipped profiles and hand-made reports.
#pragma once

#include <handemo/glove.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace glove_test {

inline handemo::glove_profile imu_profile()
{
    return handemo::read_glove_profile(std::string(HANDEMO_SOURCE_DIR) + "/examples/glove/imu7_example.json");
}
inline handemo::glove_profile flex_profile()
{
    return handemo::read_glove_profile(std::string(HANDEMO_SOURCE_DIR) + "/examples/glove/flex15_example.json");
}

/// A 64-byte report of the 7-IMU example profile: id 1, counter, millisecond clock, 7 quaternions Q14.
inline std::vector<std::uint8_t> imu_report(std::uint8_t seq, std::uint32_t ms, const std::vector<handemo::quat>& q)
{
    std::vector<std::uint8_t> b(64, 0);
    b[0] = 1;
    b[1] = seq;
    for (int i = 0; i < 4; ++i) b[2 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(ms >> (8 * i));
    for (std::size_t k = 0; k < q.size(); ++k) {
        const double c[4] = {q[k].w, q[k].x, q[k].y, q[k].z};
        for (std::size_t i = 0; i < 4; ++i) {
            const auto v = static_cast<std::int16_t>(std::lround(c[i] * 16384));
            b[6 + 8 * k + 2 * i] = static_cast<std::uint8_t>(static_cast<std::uint16_t>(v) & 0xff);
            b[6 + 8 * k + 2 * i + 1] = static_cast<std::uint8_t>(static_cast<std::uint16_t>(v) >> 8);
        }
    }
    return b;
}

inline std::vector<handemo::quat> identity7() { return std::vector<handemo::quat>(7); }

}  // namespace glove_test
