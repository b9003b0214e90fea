// From sensor readings to the 23-joint hand (hand.hpp): calibration and the per-frame pose solve.
//
// IMU gloves. Sensor k reports q_k = W R_k M_k: W the IMUs' common world frame, R_k the orientation of its
// bone, M_k how it is strapped on. Relative to the back-of-hand sensor, rel_k = q_b* q_k = M_b* S_k M_k
// with S_k = R_palm* R_k the bone's orientation in the hand frame. With the hand held flat (every finger
// angle 0, S_k = I) the calibration stores C_k = rel_k = M_b* M_k, so at run time
// S_k = M_b rel_k C_k* M_b*; only M_b, the back sensor's axes in the hand frame, must be known (the
// profile's `back_mount`). W and the finger mountings cancel.
// S_k = Rz(a) Rx(b) Ry(c) (the fingers' `Zrotation Xrotation Yrotation`) gives abduction a at the MCP
// joint (thumb: CMC), the bend b summed over the joints from MCP to the sensor's bone, and the twist c at
// the sensor's bone (a second IMU on the same finger, e.g. on the thumb, sees the joints after the
// first one the same way, relative to it). The bend is split by anatomical coupling: MCP : PIP = proximal_weight :
// intermediate_weight and DIP = distal_of_intermediate x PIP (2/3, Rijpkema & Girard 1991); joints beyond
// the sensor follow the same coupling. Every angle is then clamped to the hand model's joint limits.
// What an IMU recovers exactly is its own bone's orientation relative to the back of the hand: abduction,
// total bend and twist. The split of the bend over MCP/PIP/DIP is the coupling's assumption (an IMU on a
// finger cannot see it), the metacarpal (CMC) joints are not seen (set to 0, their bend goes to the MCP
// joint) and, at a bend of 90 degrees, abduction and twist are only seen as their sum (gimbal lock): within
// a few degrees of it the twist is shrunk toward 0 and its part of the sum goes to the abduction (twist is
// small in a real hand, abduction is not).
// The forearm, wrist and palm are left at 0 (a glove has no forearm sensor).
//
// Flex gloves. Each sensor measures one angle of one joint; calibration from a flat hand (angle 0) and a
// fist (the profile's `fist_angle`) makes the map linear: angle = (v - flat) / (fist - flat) x fist_angle.
// A distal joint without a sensor follows its intermediate joint by the same coupling.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/glove/detail/quat.hpp>
#include <handemo/glove/profile.hpp>
#include <handemo/motion/hand.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

namespace handemo {

/// @brief Calibration of one glove with one profile.
struct glove_calibration {
    std::string profile;          ///< the profile's name
    std::vector<quat> imu_flat;   ///< [imus] q_back* q_k held flat (the back sensor: q_back itself)
    std::vector<double> flex_flat, flex_fist;  ///< [flexes] raw readings flat and in a fist
};

/// @brief The calibration a profile implies without measuring: identity mountings, nominal flex values.
inline glove_calibration default_calibration(const glove_profile& p)
{
    glove_calibration c;
    c.profile = p.name;
    c.imu_flat.assign(p.imus.size(), quat{});
    for (const auto* f : p.flexes) c.flex_flat.push_back(f->flat), c.flex_fist.push_back(f->fist);
    return c;
}

/// @brief Calibrates from samples of a flat hand (IMU and flex) and of a fist (flex; empty: nominal).
/// @throws value_error when there are no flat samples, or a flex sensor reads the same flat and in a fist.
inline glove_calibration calibrate_glove(const glove_profile& p, std::span<const glove_sample> flat, std::span<const glove_sample> fist = {})
{
    if (flat.empty()) throw value_error("glove calibrate: no samples of the flat hand");
    glove_calibration c = default_calibration(p);
    const int bi = p.back_index();
    std::vector<quat> qs(flat.size());
    for (std::size_t k = 0; k < p.imus.size(); ++k) {
        for (std::size_t i = 0; i < flat.size(); ++i)
            qs[i] = static_cast<int>(k) == bi ? flat[i].imu[k] : conjugate(flat[i].imu[static_cast<std::size_t>(bi)]) * flat[i].imu[k];
        c.imu_flat[k] = average(qs);
    }
    auto mean = [](std::span<const glove_sample> s, std::size_t k) {
        double m = 0;
        for (const auto& x : s) m += x.flex[k];
        return m / static_cast<double>(s.size());
    };
    for (std::size_t k = 0; k < p.flexes.size(); ++k) {
        c.flex_flat[k] = mean(flat, k);
        if (!fist.empty() && p.flexes[k]->fist_calibrated) c.flex_fist[k] = mean(fist, k);
        const double span = std::abs(p.flexes[k]->fist - p.flexes[k]->flat);
        if (std::abs(c.flex_fist[k] - c.flex_flat[k]) < 1e-3 * span)
            throw value_error("glove calibrate: sensor '" + p.flexes[k]->name + "' reads " + std::to_string(c.flex_flat[k]) +
                              " flat and " + std::to_string(c.flex_fist[k]) + " in a fist (did the hand move?)");
    }
    return c;
}

/// @brief The calibration as JSON (`handemo-glove-calibration/1`).
inline nlohmann::json to_json(const glove_calibration& c, const glove_profile& p)
{
    nlohmann::json j{{"format", "handemo-glove-calibration/1"}, {"profile", c.profile}};
    nlohmann::json imu = nlohmann::json::object(), flex = nlohmann::json::object();
    for (std::size_t k = 0; k < c.imu_flat.size(); ++k) {
        const auto& q = c.imu_flat[k];
        imu[p.imus[k]->name] = {q.w, q.x, q.y, q.z};
    }
    for (std::size_t k = 0; k < c.flex_flat.size(); ++k) flex[p.flexes[k]->name] = {{"flat", c.flex_flat[k]}, {"fist", c.flex_fist[k]}};
    j["imu_flat"] = imu;
    j["flex"] = flex;
    return j;
}

/// @brief Reads a calibration file written for `p`.
/// @throws io_error, format_error (wrong format, another profile, a sensor missing).
inline glove_calibration read_glove_calibration(const std::filesystem::path& path, const glove_profile& p)
{
    const std::string where = "glove calibration: " + path.string();
    try {
        const auto j = nlohmann::json::parse(read_file(path));
        if (j.value("format", std::string()) != "handemo-glove-calibration/1")
            throw format_error(where + ": \"format\" is not 'handemo-glove-calibration/1'");
        glove_calibration c = default_calibration(p);
        c.profile = j.at("profile").get<std::string>();
        if (c.profile != p.name) throw format_error(where + ": made for profile '" + c.profile + "', not '" + p.name + "'");
        for (std::size_t k = 0; k < p.imus.size(); ++k) {
            const auto& v = j.at("imu_flat").at(p.imus[k]->name);
            c.imu_flat[k] = normalized({v.at(0).get<double>(), v.at(1).get<double>(), v.at(2).get<double>(), v.at(3).get<double>()});
        }
        for (std::size_t k = 0; k < p.flexes.size(); ++k) {
            const auto& v = j.at("flex").at(p.flexes[k]->name);
            c.flex_flat[k] = v.at("flat").get<double>(), c.flex_fist[k] = v.at("fist").get<double>();
        }
        return c;
    } catch (const nlohmann::json::exception& e) {
        throw format_error(where + ": " + e.what());
    }
}

inline void write_glove_calibration(const std::filesystem::path& path, const glove_calibration& c, const glove_profile& p)
{
    write_file_atomic(path, to_json(c, p).dump(2) + "\n");
}

/// @brief Solves hand poses from samples: a profile and a calibration, precomputed once.
class hand_solver {
public:
    /// @throws value_error when an IMU sits on a bone the solve does not support (finger IMUs belong on a
    /// proximal, intermediate or distal bone) or the calibration does not fit the profile.
    hand_solver(const glove_profile& p, glove_calibration c, const skeleton& hand = hand_skeleton())
        : p_(p), c_(std::move(c)), back_(p.back_index()), mount_(p.back_mount)
    {
        if (!is_hand_skeleton(hand)) throw value_error("hand_solver: the skeleton is not the 23-joint hand");
        if (c_.imu_flat.size() != p.imus.size() || c_.flex_flat.size() != p.flexes.size())
            throw value_error("hand_solver: the calibration has " + std::to_string(c_.imu_flat.size()) + " IMUs and " +
                              std::to_string(c_.flex_flat.size()) + " flex sensors, the profile " + std::to_string(p.imus.size()) +
                              " and " + std::to_string(p.flexes.size()));
        for (std::size_t j = 0; j < hand_joint_count; ++j) lo_[j] = hand.joints[j].lower_limit, hi_[j] = hand.joints[j].upper_limit;
        const auto& cp = p.coupling;
        coef_ = {cp.proximal_weight, cp.intermediate_weight, cp.distal_of_intermediate * cp.intermediate_weight};
        for (std::size_t k = 0; k < p.imus.size(); ++k) {
            if (static_cast<int>(k) == back_) continue;
            const std::size_t b = hand.index_of(p.imus[k]->bone);
            if (b < 3 || (b - 3) % 4 == 0)
                throw value_error("hand_solver: IMU '" + p.imus[k]->name + "' sits on '" + p.imus[k]->bone +
                                  "'; finger IMUs belong on a proximal, intermediate or distal bone");
            imu_.push_back({k, (b - 3) / 4, (b - 3) % 4});
        }
        std::sort(imu_.begin(), imu_.end(), [](const imu_map& a, const imu_map& b) {
            return a.finger != b.finger ? a.finger < b.finger : a.segment < b.segment;
        });
        for (std::size_t i = 1; i < imu_.size(); ++i)
            if (imu_[i].finger == imu_[i - 1].finger && imu_[i].segment == imu_[i - 1].segment)
                throw value_error("hand_solver: two IMUs on '" + p.imus[imu_[i].sensor]->bone + "'");
        for (std::size_t k = 0; k < p.flexes.size(); ++k) {
            const std::size_t b = hand.index_of(p.flexes[k]->bone);
            flex_.push_back({k, b, static_cast<std::size_t>(p.flexes[k]->rotation_axis)});
            if (p.flexes[k]->rotation_axis == axis::x && b >= 3) flex_sensed_[b] = true;
        }
        calib_inv_.resize(c_.imu_flat.size());
        for (std::size_t k = 0; k < c_.imu_flat.size(); ++k) calib_inv_[k] = conjugate(c_.imu_flat[k]);
    }

    const glove_profile& profile() const noexcept { return p_; }
    const glove_calibration& calibration() const noexcept { return c_; }

    /// @brief The orientation S_k of IMU k's bone in the hand frame (see the file comment).
    quat bone_orientation(const glove_sample& s, std::size_t k) const noexcept
    {
        const quat rel = conjugate(s.imu[static_cast<std::size_t>(back_)]) * s.imu[k];
        return mount_ * rel * calib_inv_[k] * conjugate(mount_);
    }

    /// @brief Solves one pose. @param angles [23, 3] degrees (x, y, z per joint), fully overwritten.
    void solve(const glove_sample& s, double* angles) const noexcept
    {
        std::fill(angles, angles + hand_joint_count * 3, 0.0);
        quat prev{};
        for (std::size_t i = 0; i < imu_.size(); ++i) {
            const auto& m = imu_[i];
            const quat S = bone_orientation(s, m.sensor);
            // A second IMU on the same finger (the thumb of a 7-IMU glove) sees the joints after the first.
            const bool after = i > 0 && imu_[i - 1].finger == m.finger;
            const std::size_t from = after ? imu_[i - 1].segment + 1 : 1;
            vec3 e = euler_zxy_deg(to_mat3(after ? conjugate(prev) * S : S));  // {a, b, c}
            prev = S;
            // Near b = +-90 only a + c sin(b) is seen and a - c is noise / cos(b): shrink the twist by
            // w = cos^2 b / (cos^2 b + 0.1^2) (half at 5.7 degrees from the lock, 96% kept at b = 60) and
            // keep the seen combination, so noise is not amplified into abduction and twist.
            const double cb = std::cos(e[1] * std::numbers::pi / 180), w = cb * cb / (cb * cb + lock_eps * lock_eps);
            const double c = w * e[2];
            e[0] += (e[2] - c) * (e[1] >= 0 ? 1.0 : -1.0);
            e[2] = c;
            double sum = 0;
            for (std::size_t seg = from; seg <= m.segment; ++seg) sum += coef_[seg - 1];
            for (std::size_t seg = from; seg <= 3; ++seg)
                angles[hand_index::finger_joint(m.finger, seg) * 3 + 0] = sum > 0 ? coef_[seg - 1] * e[1] / sum : (seg == m.segment ? e[1] : 0);
            angles[hand_index::finger_joint(m.finger, from) * 3 + 2] = e[0];
            angles[hand_index::finger_joint(m.finger, m.segment) * 3 + 1] = e[2];
        }
        for (const auto& m : flex_) {
            const double flat = c_.flex_flat[m.sensor], fist = c_.flex_fist[m.sensor];
            angles[m.joint * 3 + m.axis] = (s.flex[m.sensor] - flat) / (fist - flat) * p_.flexes[m.sensor]->fist_angle;
        }
        for (std::size_t f = 0; f < hand_finger_count; ++f) {
            const std::size_t mid = hand_index::finger_joint(f, 2), tip = hand_index::finger_joint(f, 3);
            if (flex_sensed_[mid] && !flex_sensed_[tip]) angles[tip * 3] = p_.coupling.distal_of_intermediate * angles[mid * 3];
        }
        for (std::size_t j = 0; j < hand_joint_count; ++j)
            for (std::size_t a = 0; a < 3; ++a) angles[j * 3 + a] = std::clamp(angles[j * 3 + a], lo_[j][a], hi_[j][a]);
    }

private:
    static constexpr double lock_eps = 0.1;  ///< |cos b| at which half the twist is kept (b 5.7 deg from 90)
    struct imu_map {
        std::size_t sensor, finger, segment;
    };
    struct flex_map {
        std::size_t sensor, joint, axis;
    };
    glove_profile p_;
    glove_calibration c_;
    int back_;
    quat mount_;
    std::array<double, 3> coef_{};
    std::vector<imu_map> imu_;
    std::vector<flex_map> flex_;
    std::vector<quat> calib_inv_;
    std::array<bool, hand_joint_count> flex_sensed_{};
    std::array<vec3, hand_joint_count> lo_{}, hi_{};
};

/// @brief Simulated glove readings of known hand poses (tests, `handemo glove simulate`): IMU k reads
/// W R_k M_k with a random world frame W and random strap-on rotations M_k (within `mount_spread_deg`;
/// the back sensor's is the profile's back_mount); a flex sensor reads the nominal flat/fist map of its
/// joint angle, clamped to its range.
class glove_simulator {
public:
    explicit glove_simulator(const glove_profile& p, std::uint64_t seed = 1, double mount_spread_deg = 20)
        : p_(p), hand_(hand_skeleton())
    {
        std::mt19937_64 g(seed);
        auto rand_rot = [&](double spread_deg) {
            std::uniform_real_distribution<double> u(-1, 1);
            vec3 ax{u(g), u(g), u(g)};
            const double n = std::sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]) + 1e-12;
            const double ang = spread_deg * std::abs(u(g)) * std::numbers::pi / 180, s = std::sin(ang / 2);
            return quat{std::cos(ang / 2), s * ax[0] / n, s * ax[1] / n, s * ax[2] / n};
        };
        world_ = rand_rot(180);
        for (std::size_t k = 0; k < p.imus.size(); ++k) {
            mounts_.push_back(static_cast<int>(k) == p.back_index() ? p.back_mount : rand_rot(mount_spread_deg));
            bones_.push_back(hand_.index_of(p.imus[k]->bone));
        }
        for (const auto* f : p.flexes) bones_flex_.push_back(hand_.index_of(f->bone));
    }
    /// @brief The sample of pose `angles` ([23, 3] degrees) at time `t`.
    glove_sample sample(const double* angles, double t) const
    {
        glove_sample s;
        s.host_time = t;
        const auto fk = forward_kinematics(hand_, angles);
        for (std::size_t k = 0; k < bones_.size(); ++k) s.imu.push_back(normalized(world_ * from_mat3(fk.rotations[bones_[k]]) * mounts_[k]));
        for (std::size_t k = 0; k < bones_flex_.size(); ++k) {
            const auto* f = p_.flexes[k];
            const double v = f->flat + angles[bones_flex_[k] * 3 + static_cast<std::size_t>(f->rotation_axis)] / f->fist_angle * (f->fist - f->flat);
            s.flex.push_back(std::clamp(v, f->range_min, f->range_max));
        }
        return s;
    }

private:
    glove_profile p_;
    skeleton hand_;
    quat world_;
    std::vector<quat> mounts_;
    std::vector<std::size_t> bones_, bones_flex_;
};

}  // namespace handemo
