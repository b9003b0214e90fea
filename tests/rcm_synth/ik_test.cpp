// The damped least-squares IK: bone lengths exactly kept, joint limits respected, reachable targets reached;
// its Jacobian checked against finite differences of its forward kinematics, which agrees with forward_kinematics.
#include "helpers.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>

using namespace handemo;

namespace {

std::vector<rcm::ik_target> targets_of(const skeleton& s, const std::vector<double>& ang, const std::vector<double>& pos,
                                       const std::vector<rcm::skeleton_point>& pts)
{
    const auto fk = forward_kinematics(s, ang.data(), pos.data());
    std::vector<rcm::ik_target> t;
    for (const auto& p : pts) {
        const auto j = static_cast<std::size_t>(p.joint);
        t.push_back({p, p.end_site ? fk.end_sites[j] : fk.joints[j], 1.0});
    }
    return t;
}

double max_distance(const skeleton& s, const std::vector<double>& ang, const std::vector<double>& pos,
                    const std::vector<rcm::ik_target>& tg)
{
    const auto fk = forward_kinematics(s, ang.data(), pos.data());
    double m = 0;
    for (const auto& t : tg) {
        const auto j = static_cast<std::size_t>(t.point.joint);
        const vec3 p = t.point.end_site ? fk.end_sites[j] : fk.joints[j];
        m = std::max(m, std::hypot(p[0] - t.position[0], p[1] - t.position[1], p[2] - t.position[2]));
    }
    return m;
}

}  // namespace

TEST_CASE("rcm ik: the hand reaches reachable wrist and tip targets within its joint limits")
{
    const skeleton s = hand_skeleton();
    const rcm::rig r = rcm::make_rig(s);
    rcm::ik_solver ik(s, r.translation_joint);
    std::mt19937 rng(3);
    int reached = 0;
    for (int trial = 0; trial < 10; ++trial) {
        // A random pose inside the limits is the answer; start from another one nearby.
        std::vector<double> goal(s.size() * 3), start(s.size() * 3), pos(s.size() * 3);
        for (std::size_t j = 0; j < s.size(); ++j)
            for (std::size_t a = 0; a < 3; ++a) {
                const double lo = s.joints[j].lower_limit[a], hi = s.joints[j].upper_limit[a];
                std::uniform_real_distribution<double> u(lo, hi);
                goal[j * 3 + a] = u(rng);
                start[j * 3 + a] = std::clamp(goal[j * 3 + a] + std::uniform_real_distribution<double>(-15, 15)(rng), lo, hi);
                pos[j * 3 + a] = s.joints[j].offset[a];
            }
        const auto tg = targets_of(s, goal, pos, r.points);
        auto q = start;
        auto p = pos;
        p[0] += 0.5;  // the forearm starts 5 mm off
        const auto rep = ik.solve(q, p, tg);
        CHECK(rep.rms_after <= rep.rms_before);
        for (std::size_t j = 0; j < s.size(); ++j)
            for (std::size_t a = 0; a < 3; ++a) {
                CHECK(q[j * 3 + a] >= s.joints[j].lower_limit[a] - 1e-12);
                CHECK(q[j * 3 + a] <= s.joints[j].upper_limit[a] + 1e-12);
            }
        if (max_distance(s, q, p, tg) < 1e-3) ++reached;
    }
    CHECK(reached >= 9);
}

TEST_CASE("rcm ik: a body reaches moved pelvis, head and hand targets with feet pinned; bones keep their lengths")
{
    const clip c = test::humanoid_dance(30);
    const rcm::rig r = rcm::make_rig(c.skel);
    rcm::ik_solver ik(c.skel, r.translation_joint);
    const std::size_t J3 = c.skel.size() * 3;
    for (std::size_t f : {0u, 7u, 19u}) {
        // The answer: the dance's pose f with other angles (reachable by construction); start from frame f.
        std::vector<double> goal(c.frame_angles(f), c.frame_angles(f) + J3), pos(c.frame_positions(f), c.frame_positions(f) + J3);
        for (std::size_t i = 3; i < J3; ++i) goal[i] += 12.0 * std::sin(static_cast<double>(i) * 1.7 + static_cast<double>(f));
        auto gpos = pos;
        gpos[1] -= 6.0;  // pelvis 6 cm lower
        const auto tg = targets_of(c.skel, goal, gpos, r.points);
        std::vector<double> q(c.frame_angles(f), c.frame_angles(f) + J3), p = pos;
        const double before = max_distance(c.skel, q, p, tg);
        rcm::ik_options o;
        o.max_iterations = 100;
        rcm::ik_solver ik2(c.skel, r.translation_joint, o);
        ik2.solve(q, p, tg);
        CHECK(before > 5.0);
        CHECK(max_distance(c.skel, q, p, tg) < 1e-3);
        // bone lengths: every joint's distance to its parent equals the rest offset's length (to rounding)
        const auto fk = forward_kinematics(c.skel, q.data(), p.data());
        for (std::size_t j = 1; j < c.skel.size(); ++j) {
            const auto pj = static_cast<std::size_t>(c.skel.joints[j].parent);
            const auto& o3 = c.skel.joints[j].offset;
            const double rest = std::hypot(o3[0], o3[1], o3[2]);
            CHECK(std::hypot(fk.joints[j][0] - fk.joints[pj][0], fk.joints[j][1] - fk.joints[pj][1],
                             fk.joints[j][2] - fk.joints[pj][2]) == doctest::Approx(rest).epsilon(1e-12));
        }
    }
}

TEST_CASE("rcm ik: unreachable targets leave limits and bone lengths intact and reduce the error")
{
    const skeleton s = hand_skeleton();
    const rcm::rig r = rcm::make_rig(s);
    rcm::ik_solver ik(s, -1);  // forearm fixed: the tips cannot reach a point 1 m away
    std::vector<double> q(s.size() * 3, 0.0), p(s.size() * 3);
    for (std::size_t j = 0; j < s.size(); ++j)
        for (int a = 0; a < 3; ++a) p[j * 3 + a] = s.joints[j].offset[a];
    std::vector<rcm::ik_target> tg;
    for (std::size_t f = 0; f < 5; ++f) tg.push_back({r.points[2 + f], {0.0, -100.0, 30.0}, 1.0});
    const auto rep = ik.solve(q, p, tg);
    CHECK(rep.rms_after < rep.rms_before);
    for (std::size_t j = 0; j < s.size(); ++j)
        for (std::size_t a = 0; a < 3; ++a) {
            CHECK(q[j * 3 + a] >= s.joints[j].lower_limit[a] - 1e-12);
            CHECK(q[j * 3 + a] <= s.joints[j].upper_limit[a] + 1e-12);
        }
    bool some_at_limit = false;
    for (std::size_t j = 0; j < s.size(); ++j)
        for (std::size_t a = 0; a < 3; ++a)
            some_at_limit = some_at_limit || q[j * 3 + a] == s.joints[j].upper_limit[a] || q[j * 3 + a] == s.joints[j].lower_limit[a];
    CHECK(some_at_limit);
    CHECK_THROWS_AS(ik.solve(q, p, std::vector<rcm::ik_target>{{{99, false}, {}, 1.0}}), shape_error);
}

namespace {

double rms_of(const skeleton& s, const std::vector<double>& ang, const std::vector<double>& pos, const std::vector<rcm::ik_target>& tg)
{
    const auto fk = forward_kinematics(s, ang.data(), pos.data());
    double e = 0, w = 0;
    for (const auto& t : tg) {
        const auto j = static_cast<std::size_t>(t.point.joint);
        const vec3 p = t.point.end_site ? fk.end_sites[j] : fk.joints[j];
        for (int c = 0; c < 3; ++c) e += t.weight * (p[c] - t.position[c]) * (p[c] - t.position[c]);
        w += t.weight;
    }
    return std::sqrt(e / w);
}

bool within_limits(const skeleton& s, const std::vector<double>& q)
{
    for (std::size_t j = 0; j < s.size(); ++j)
        for (std::size_t a = 0; a < 3; ++a)
            if (q[j * 3 + a] < s.joints[j].lower_limit[a] - 1e-12 || q[j * 3 + a] > s.joints[j].upper_limit[a] + 1e-12) return false;
    return true;
}

}  // namespace

TEST_CASE("rcm ik: the stall rule stops early on unreachable targets and returns the best pose seen")
{
    const skeleton s = hand_skeleton();
    const rcm::rig r = rcm::make_rig(s);
    std::vector<double> q0(s.size() * 3, 0.0), p(s.size() * 3);
    for (std::size_t j = 0; j < s.size(); ++j)
        for (int a = 0; a < 3; ++a) p[j * 3 + a] = s.joints[j].offset[a];
    std::vector<rcm::ik_target> tg;  // forearm fixed, tips 1 m away: out of reach
    for (std::size_t f = 0; f < 5; ++f) tg.push_back({r.points[2 + f], {0.0, -100.0, 30.0}, 1.0});
    rcm::ik_options stall;
    stall.max_iterations = 200;
    stall.stall_tolerance = 1e-3;
    stall.stall_iterations = 2;
    rcm::ik_options off = stall;
    off.stall_tolerance = 0;  // an accepted step always lowers the error: never stalls
    auto q = q0;
    const auto rep = rcm::ik_solver(s, -1, stall).solve(q, p, tg);
    auto q_off = q0;
    const auto rep_off = rcm::ik_solver(s, -1, off).solve(q_off, p, tg);
    MESSAGE("unreachable: stall rule " << rep.iterations << " iterations, rms " << rep.rms_after << "; without it "
                                       << rep_off.iterations << " iterations, rms " << rep_off.rms_after);
    CHECK(rep.iterations < rep_off.iterations / 2);
    CHECK(rep.rms_after < rep.rms_before);
    CHECK(rep.rms_after <= 1.02 * rep_off.rms_after);  // what the extra iterations would still gain is small (1.3%)
    // the pose returned is the one whose distance is reported, and no pose seen on the way was nearer
    CHECK(rms_of(s, q, p, tg) == doctest::Approx(rep.rms_after).epsilon(1e-9));
    double prev = rep.rms_before;
    for (int it = 1; it <= rep.iterations; ++it) {
        rcm::ik_options o = stall;
        o.max_iterations = it;
        auto qi = q0;
        const auto ri = rcm::ik_solver(s, -1, o).solve(qi, p, tg);
        CHECK(ri.rms_after <= prev);
        prev = ri.rms_after;
    }
    CHECK(prev == rep.rms_after);
    CHECK(within_limits(s, q));
}

TEST_CASE("rcm ik: a warm start from the previous solution does as well or better than a cold start on nearby targets")
{
    // A hand sequence as the synthesis sees it: keyframe inputs 5 frames apart, targets that move the tips
    // 3 cm away from the palm (partly out of reach), solved once from each input (cold) and once also offered
    // the previous keyframe's change (warm).
    const clip c = synthesize(hand_motion::pointing, emotion::neutral, 0, 2, 30.0);
    const rcm::rig r = rcm::make_rig(c.skel);
    const std::size_t J3 = c.skel.size() * 3;
    double cold_ss = 0, warm_ss = 0;
    int used = 0, cold_iters = 0, warm_iters = 0;
    std::vector<double> prev_in_a, prev_in_p, prev_out_a, prev_out_p;
    rcm::ik_options o;
    o.stall_tolerance = 1e-3;  // stylise's default with the warm start
    o.stall_iterations = 2;
    rcm::ik_solver ik(c.skel, r.translation_joint, o);
    for (std::size_t f = 0; f < c.frames; f += 5) {
        const std::vector<double> a(c.frame_angles(f), c.frame_angles(f) + J3), pos(c.frame_positions(f), c.frame_positions(f) + J3);
        const auto fk = forward_kinematics(c.skel, a.data(), pos.data());
        std::vector<rcm::ik_target> tg;
        const vec3 palm = fk.joints[static_cast<std::size_t>(r.points[1].joint)];
        for (std::size_t k = 0; k < 7; ++k) {
            const auto& pt = r.points[k];
            vec3 x = pt.end_site ? fk.end_sites[static_cast<std::size_t>(pt.joint)] : fk.joints[static_cast<std::size_t>(pt.joint)];
            if (k >= 2) {
                const double d = std::hypot(x[0] - palm[0], x[1] - palm[1], x[2] - palm[2]);
                for (int e = 0; e < 3; ++e) x[e] += 3.0 * (x[e] - palm[e]) / d;
            }
            tg.push_back({pt, x, r.ik_weights[k]});
        }
        auto qc = a, pc = pos;
        const auto rc = ik.solve(qc, pc, tg);
        auto qw = a, pw = pos;
        std::vector<double> sa(J3), sp(J3);
        rcm::ik_report rw;
        if (prev_in_a.empty()) {
            rw = ik.solve(qw, pw, tg);
        } else {
            for (std::size_t i = 0; i < J3; ++i) {
                sa[i] = a[i] + prev_out_a[i] - prev_in_a[i];
                sp[i] = pos[i] + prev_out_p[i] - prev_in_p[i];
            }
            rw = ik.solve(qw, pw, tg, sa, sp);
        }
        CHECK(within_limits(c.skel, qw));
        CHECK(rw.rms_after <= rw.rms_before);
        CHECK(rms_of(c.skel, qw, pw, tg) == doctest::Approx(rw.rms_after).epsilon(1e-9));
        used += rw.warm;
        cold_ss += rc.rms_after * rc.rms_after;
        warm_ss += rw.rms_after * rw.rms_after;
        cold_iters += rc.iterations;
        warm_iters += rw.iterations;
        prev_in_a = a, prev_in_p = pos, prev_out_a = qw, prev_out_p = pw;
    }
    MESSAGE("hand sequence: cold rms " << std::sqrt(cold_ss) << " (" << cold_iters << " iterations), warm rms " << std::sqrt(warm_ss)
                                       << " (" << warm_iters << " iterations), warm start taken " << used << " times");
    CHECK(used > 0);
    CHECK(warm_ss <= cold_ss * (1 + 1e-9));

    // A start that already solves a reachable problem is taken and needs no step.
    const std::vector<double> a(c.frame_angles(0), c.frame_angles(0) + J3), pos(c.frame_positions(0), c.frame_positions(0) + J3);
    const auto goal = c.frame_angles(c.frames / 2);
    const std::vector<double> ga(goal, goal + J3);
    const auto tg = targets_of(c.skel, ga, pos, r.points);
    auto q = a, p = pos;
    const auto rep = ik.solve(q, p, tg, ga, pos);
    CHECK(rep.warm);
    CHECK(rep.iterations == 0);
    CHECK(q == ga);
    std::vector<double> bad(3);
    CHECK_THROWS_AS(ik.solve(q, p, tg, bad, bad), shape_error);
}

namespace {

// The skeletons of the Jacobian check: the hand (forearm translation, the hand's limits), the test humanoid
// (pelvis translation, +-180 everywhere: unlimited), the humanoid with its joints' rotation orders cycled
// through all six permutations (the pelvis's too), so that every order of the world axes is exercised, and
// the humanoid under a rotating root joint without position channels (the translation's derivative is then
// the root's rotation, not the identity). The translation joint is the first with position channels.
struct kin_case {
    std::string name;
    skeleton s;
};

int first_translation_joint(const skeleton& s)
{
    for (std::size_t j = 0; j < s.size(); ++j)
        if (s.joints[j].has_position()) return static_cast<int>(j);
    return -1;
}

std::vector<kin_case> kin_cases()
{
    std::vector<kin_case> out{{"hand", hand_skeleton()}, {"body", test::humanoid()}, {"body, all rotation orders", test::humanoid()}};
    constexpr std::array<std::array<channel, 3>, 6> orders{{
        {channel::xrotation, channel::yrotation, channel::zrotation}, {channel::xrotation, channel::zrotation, channel::yrotation},
        {channel::yrotation, channel::xrotation, channel::zrotation}, {channel::yrotation, channel::zrotation, channel::xrotation},
        {channel::zrotation, channel::xrotation, channel::yrotation}, {channel::zrotation, channel::yrotation, channel::xrotation},
    }};
    for (std::size_t j = 0; j < out[2].s.size(); ++j) {
        joint& jt = out[2].s.joints[j];
        const auto& o = orders[(j + 1) % 6];
        if (jt.has_position())
            jt.channels = {channel::xposition, channel::yposition, channel::zposition, o[0], o[1], o[2]};
        else
            jt.channels = {o[0], o[1], o[2]};
    }
    kin_case rooted{"body under a rotating root", test::humanoid()};
    joint root;
    root.name = "Root";
    root.offset = {3, 1, -2};
    rooted.s.joints.insert(rooted.s.joints.begin(), root);
    for (std::size_t j = 1; j < rooted.s.size(); ++j) rooted.s.joints[j].parent += 1;
    rooted.s.validate();
    out.push_back(std::move(rooted));
    return out;
}

// A pose q (dof_layout order) and the position-channel values: kind 0 every angle uniform inside its limits;
// kind 1 every angle at one of its limits, or within 1e-6 degrees inside it (the humanoid's +-180 included);
// kind 2 half of the angles so, half inside. The translation is the rest offset moved by up to 20 cm.
void kin_pose(const skeleton& s, int tj, int kind, std::mt19937& rng, std::vector<double>& q, std::vector<double>& pos)
{
    const std::size_t J = s.size();
    q.assign(J * 3 + (tj >= 0 ? 3 : 0), 0.0);
    pos.assign(J * 3, 0.0);
    std::uniform_real_distribution<double> u(0, 1);
    for (std::size_t j = 0; j < J; ++j)
        for (std::size_t a = 0; a < 3; ++a) {
            const double lo = s.joints[j].lower_limit[a], hi = s.joints[j].upper_limit[a];
            const bool at_limit = kind == 1 || (kind == 2 && u(rng) < 0.5);
            if (!at_limit) {
                q[j * 3 + a] = lo + (hi - lo) * u(rng);
            } else {
                const double inside = u(rng) < 1.0 / 3 ? 0.0 : 1e-6 * u(rng);
                q[j * 3 + a] = u(rng) < 0.5 ? lo + inside : hi - inside;
            }
            pos[j * 3 + a] = s.joints[j].offset[a];
        }
    if (tj >= 0)
        for (std::size_t c = 0; c < 3; ++c) q[J * 3 + c] = pos[static_cast<std::size_t>(tj) * 3 + c] + 40.0 * (u(rng) - 0.5);
}

// A target at every joint's origin and every End Site: positions up to 50 cm from the origin, weights in
// [0.2, 2] (and one 0 to check that a weightless target contributes nothing).
std::vector<rcm::ik_target> all_targets(const skeleton& s, std::mt19937& rng)
{
    std::uniform_real_distribution<double> u(-50, 50), w(0.2, 2.0);
    std::vector<rcm::ik_target> tg;
    for (std::size_t j = 0; j < s.size(); ++j) {
        tg.push_back({{static_cast<int>(j), false}, {u(rng), u(rng), u(rng)}, w(rng)});
        if (s.joints[j].end_site) tg.push_back({{static_cast<int>(j), true}, {u(rng), u(rng), u(rng)}, w(rng)});
    }
    tg[tg.size() / 2].weight = 0.0;
    return tg;
}

}  // namespace

// The solver's analytic Jacobian (ik_kinematics::add_residual_jacobian, the code solve() runs: columns
// -sqrt(w) (w x (p - o)) pi/180 from the world axes, -sqrt(w) R_parent for the translation) of the residuals
// r = sqrt(weight) (target - p) against central differences of the same residuals through the solver's own
// forward kinematics (ik_kinematics::forward), for every DOF the solver has (all 3 angles of every joint, the
// 3 translation values) and a target at every point it can target (every joint origin and End Site).
// Steps: 1e-3 degrees for an angle, 1e-3 cm for the translation. The central difference's truncation error
// is h^2/6 |d3r/dq3| <= (1e-3 pi/180)^2 / 6 * 1.5 * 200 cm ~ 1e-10 cm per degree and its rounding ~ 1e-16 *
// 300 cm / 1e-3 = 3e-11, so every entry must satisfy |J - FD| <= 1e-8 + 1e-6 |FD| (cm per degree, or cm per
// cm). Entries of a moving DOF are up to 3 cm per degree: a wrong sign, axis, order or scale fails by orders
// of magnitude, and the check requires the columns to be far above the tolerance (not vacuously zero).
TEST_CASE("rcm ik: the solver's Jacobian matches central finite differences of its forward kinematics "
          "(hand and body, random poses and poses at the joint limits)")
{
    constexpr double h = 1e-3, atol = 1e-8, rtol = 1e-6;
    std::mt19937 rng(17);
    for (const kin_case& kc : kin_cases()) {
        const skeleton& s = kc.s;
        const int tj = first_translation_joint(s);
        REQUIRE(tj >= 0);
        const rcm::ik_solver solver(s, tj);
        const rcm::detail::ik_kinematics& kin = solver.kinematics();
        const std::size_t n = kin.layout().size();
        REQUIRE(n == s.size() * 3 + 3);
        REQUIRE(n == solver.dof_count());
        const auto tg = all_targets(s, rng);
        const std::size_t m = tg.size() * 3;
        auto st = kin.make_state();
        std::vector<double> q, pos, r0(m), jac(m * n), fd(m * n), plus(m), minus(m);
        auto residuals_at = [&](const std::vector<double>& qq, std::vector<double>& out) {
            kin.forward(qq.data(), pos.data(), st, false);
            for (std::size_t k = 0; k < tg.size(); ++k)
                for (std::size_t c = 0; c < 3; ++c)
                    out[k * 3 + c] = std::sqrt(tg[k].weight) * (tg[k].position[c] - rcm::detail::ik_kinematics::point(st, tg[k].point)[c]);
        };
        double worst = 0, worst_err = 0;
        for (int trial = 0; trial < 9; ++trial) {
            const int kind = trial % 3;
            CAPTURE(kc.name);
            CAPTURE(trial);
            kin_pose(s, tj, kind, rng, q, pos);
            kin.residuals_with_jacobian(q.data(), pos.data(), tg, r0.data(), jac.data());
            std::vector<double> r1(m);
            residuals_at(q, r1);
            CHECK(r1 == r0);  // the residuals beside the Jacobian are the forward kinematics'
            for (std::size_t c = 0; c < n; ++c) {
                auto qp = q, qm = q;
                qp[c] += h;
                qm[c] -= h;
                residuals_at(qp, plus);
                residuals_at(qm, minus);
                for (std::size_t r = 0; r < m; ++r) fd[r * n + c] = (plus[r] - minus[r]) / (2 * h);
            }
            std::size_t bad = 0;
            std::vector<double> col_max(n, 0.0);
            for (std::size_t c = 0; c < n; ++c) {
                double col = 0;
                for (std::size_t r = 0; r < m; ++r) {
                    const double a = jac[r * n + c], f = fd[r * n + c], e = std::abs(a - f);
                    col = std::max(col, std::abs(f));
                    worst = std::max(worst, e / (atol + rtol * std::abs(f)));
                    worst_err = std::max(worst_err, e);
                    if (e > atol + rtol * std::abs(f)) {
                        if (bad++ < 5)
                            MESSAGE(kc.name << " pose " << trial << ": d r " << r / 3 << "[" << r % 3 << "] / d q[" << c
                                            << "] analytic " << a << ", finite differences " << f);
                    }
                }
                col_max[c] = col;
            }
            CHECK(bad == 0);
            // Not vacuous: every joint with a child or an End Site has at least two of its three angles that
            // move some residual by >= 1e-5 cm per degree, 1000 times the absolute tolerance (a rotation about the
            // line through which its whole subtree lies moves nothing; a distal joint flexed 90 degrees, in
            // gimbal lock, moves its End Site by ~1e-3 about the other two), and every translation value moves
            // residuals by >= 0.2 cm per cm.
            std::vector<char> moves(s.size(), 0);
            for (std::size_t j = 0; j < s.size(); ++j) {
                if (s.joints[j].end_site) moves[j] = 1;
                if (s.joints[j].parent >= 0) moves[static_cast<std::size_t>(s.joints[j].parent)] = 1;
            }
            std::size_t weak = 0;
            for (std::size_t j = 0; j < s.size(); ++j)
                if (moves[j])
                    weak += (col_max[j * 3] >= 1e-5) + (col_max[j * 3 + 1] >= 1e-5) + (col_max[j * 3 + 2] >= 1e-5) < 2;
            CHECK(weak == 0);
            for (std::size_t c = s.size() * 3; c < n; ++c) CHECK(col_max[c] >= 0.2);
        }
        // the weightless target's rows are exactly zero
        const std::size_t zero_row = (tg.size() / 2) * 3;
        for (std::size_t e = zero_row * n; e < (zero_row + 3) * n; ++e) CHECK(jac[e] == 0.0);
        MESSAGE(kc.name << ": worst |J - FD| " << worst_err << " cm per unit, " << worst << " of the tolerance");
    }
}

// ik_kinematics::forward (the solver's, rotations applied to two columns in place) and forward_kinematics
// (the library's, matrix products) compute the same pose: joint origins, End Sites and global rotations agree
// to 1e-12 relative (cm; rotations absolute) on the same skeletons and poses.
TEST_CASE("rcm ik: the solver's forward kinematics agrees with forward_kinematics")
{
    std::mt19937 rng(23);
    for (const kin_case& kc : kin_cases()) {
        const skeleton& s = kc.s;
        const int tj = first_translation_joint(s);
        const rcm::detail::ik_kinematics kin(s, tj);
        auto st = kin.make_state();
        std::vector<double> q, pos;
        for (int trial = 0; trial < 9; ++trial) {
            CAPTURE(kc.name);
            CAPTURE(trial);
            kin_pose(s, tj, trial % 3, rng, q, pos);
            kin.forward(q.data(), pos.data(), st, true);
            for (std::size_t c = 0; c < 3; ++c) pos[static_cast<std::size_t>(tj) * 3 + c] = q[s.size() * 3 + c];
            const auto fk = forward_kinematics(s, q.data(), pos.data());
            double worst_p = 0, worst_r = 0;
            for (std::size_t j = 0; j < s.size(); ++j) {
                for (std::size_t c = 0; c < 3; ++c) {
                    worst_p = std::max(worst_p, std::abs(st.org[j][c] - fk.joints[j][c]) / (1 + std::abs(fk.joints[j][c])));
                    worst_p = std::max(worst_p, std::abs(st.tip[j][c] - fk.end_sites[j][c]) / (1 + std::abs(fk.end_sites[j][c])));
                }
                for (std::size_t e = 0; e < 9; ++e) worst_r = std::max(worst_r, std::abs(st.R[j][e] - fk.rotations[j][e]));
            }
            CHECK(worst_p <= 1e-12);
            CHECK(worst_r <= 1e-12);
        }
    }
    // A translation joint without position channels is refused, as by the solver.
    const skeleton hand = hand_skeleton();
    CHECK_THROWS_AS(rcm::detail::ik_kinematics(hand, 1), value_error);
    CHECK_THROWS_AS(rcm::ik_solver(hand, 1), value_error);
}
