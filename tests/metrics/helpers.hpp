// Hand-made clips with known answers for the metrics tests.
#pragma once

#include <handemo/motion/clip.hpp>
#include <handemo/motion/hand.hpp>

#include <cmath>
#include <numbers>

namespace handemo::metrics::test {

/// A clip on the hand skeleton whose every channel k is offset + amp * sin(2 pi cycles f / (n - 1) + k / 7).
inline clip sine_clip(std::size_t n, double fps, double amp, double offset = 0.0, double cycles = 1.0)
{
    clip c = clip::make(hand_skeleton(), n, fps);
    const std::size_t J3 = c.skel.size() * 3;
    for (std::size_t f = 0; f < n; ++f)
        for (std::size_t k = 0; k < J3; ++k)
            c.angles[f * J3 + k] =
                offset + amp * std::sin(2 * std::numbers::pi * cycles * static_cast<double>(f) / static_cast<double>(n - 1) +
                                        static_cast<double>(k) / 7.0);
    return c;
}

}  // namespace handemo::metrics::test
