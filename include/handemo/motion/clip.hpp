// A motion clip: frames x joints x 3 joint angles in degrees (Eq. 1 of the hand paper, P_j), a frame
// rate, a skeleton, and the values of position channels (root translation, or every joint's in files
// such as Bandai's where all joints carry 6 channels).
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/skeleton.hpp>

#include <cmath>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

/// @brief A motion clip of any skeleton.
struct clip {
    skeleton skel;
    double fps = 30.0;
    std::size_t frames = 0;
    std::vector<double> angles;     ///< [frames, J, 3] degrees, components x, y, z
    std::vector<double> positions;  ///< [frames, J, 3] position-channel values (offsets where a joint has none)

    std::size_t joint_count() const noexcept { return skel.size(); }
    double duration() const noexcept { return frames > 0 ? static_cast<double>(frames) / fps : 0.0; }

    double& angle(std::size_t f, std::size_t j, std::size_t c) noexcept { return angles[(f * skel.size() + j) * 3 + c]; }
    double angle(std::size_t f, std::size_t j, std::size_t c) const noexcept { return angles[(f * skel.size() + j) * 3 + c]; }
    double& position(std::size_t f, std::size_t j, std::size_t c) noexcept { return positions[(f * skel.size() + j) * 3 + c]; }
    double position(std::size_t f, std::size_t j, std::size_t c) const noexcept { return positions[(f * skel.size() + j) * 3 + c]; }
    const double* frame_angles(std::size_t f) const noexcept { return angles.data() + f * skel.size() * 3; }
    const double* frame_positions(std::size_t f) const noexcept { return positions.data() + f * skel.size() * 3; }

    /// @brief Allocates a clip of `n` frames with zero angles and rest offsets as positions.
    static clip make(skeleton s, std::size_t n, double fps)
    {
        clip c;
        c.skel = std::move(s);
        c.fps = fps;
        c.frames = n;
        const std::size_t J = c.skel.size();
        c.angles.assign(n * J * 3, 0.0);
        c.positions.assign(n * J * 3, 0.0);
        for (std::size_t f = 0; f < n; ++f)
            for (std::size_t j = 0; j < J; ++j)
                for (std::size_t k = 0; k < 3; ++k) c.position(f, j, k) = c.skel.joints[j].offset[k];
        return c;
    }

    /// @brief Checks sizes, frame rate and finiteness.
    /// @throws shape_error or value_error naming `what` (usually the file) and the field.
    void validate(std::string_view what = "clip") const
    {
        skel.validate(what);
        const auto who = [&] { return std::string(what); };  // built only on an error
        const std::size_t n = frames * skel.size() * 3;
        if (angles.size() != n || positions.size() != n)
            throw shape_error(who() + ": angle/position arrays hold " + std::to_string(angles.size()) + "/" +
                              std::to_string(positions.size()) + " values, expected frames*joints*3 = " +
                              std::to_string(n));
        if (!(fps > 0) || !std::isfinite(fps)) throw value_error(who() + ": frame rate " + std::to_string(fps) + " is not positive");
        for (std::size_t i = 0; i < n; ++i) {
            if (!std::isfinite(angles[i]) || !std::isfinite(positions[i])) {
                const std::size_t f = i / (skel.size() * 3), j = (i / 3) % skel.size();
                throw value_error(who() + ": frame " + std::to_string(f) + " joint '" + skel.joints[j].name +
                                  "' has a non-finite value");
            }
        }
    }

    /// @brief Makes this clip `frames` frames of `s` at `fps`, every angle 0 and every position the joint's rest
    /// offset, as make() does, reusing this clip's storage: no allocation when it already holds as many
    /// values and a skeleton with names as long.
    void reset(const skeleton& s, std::size_t n, double rate)
    {
        skel = s;
        fps = rate;
        frames = n;
        const std::size_t J = skel.size();
        angles.assign(n * J * 3, 0.0);
        positions.resize(n * J * 3);
        for (std::size_t f = 0; f < n; ++f)
            for (std::size_t j = 0; j < J; ++j)
                for (std::size_t k = 0; k < 3; ++k) position(f, j, k) = skel.joints[j].offset[k];
    }
};

}  // namespace handemo
