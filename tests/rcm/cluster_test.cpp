// Section 3.5: Eq. 5's pose distance and hierarchical clustering of poses.
#include <handemo/rcm.hpp>
#include <handemo/motion.hpp>

#include <doctest/doctest.h>

#include <cmath>

using namespace handemo;
using doctest::Approx;

namespace {

rcm::quaternion about_x(double rad) { return {std::cos(rad / 2), std::sin(rad / 2), 0, 0}; }

/// A three-joint chain: root, then two children.
skeleton chain()
{
    skeleton s;
    s.name = "chain";
    joint r{"Hips", -1, {0, 100, 0}};
    r.channels = {channel::xposition, channel::yposition, channel::zposition, channel::zrotation, channel::xrotation, channel::yrotation};
    s.joints = {r, joint{"Spine", 0, {0, 10, 0}}, joint{"Head", 1, {0, 10, 0}}};
    return s;
}

}  // namespace

TEST_CASE("cluster: |log(q_u^-1 q_v)|^2 is (theta / 2)^2")
{
    CHECK(rcm::quaternion_log_distance2(about_x(0), about_x(0.8)) == Approx(0.16));
    CHECK(rcm::quaternion_log_distance2(about_x(0.3), about_x(-0.3)) == Approx(0.09));
    // q and -q are the same rotation
    const auto q = about_x(0.5);
    CHECK(rcm::quaternion_log_distance2(q, {-q[0], -q[1], -q[2], -q[3]}) == Approx(0.0));
    const mat3 m = axis_rotation(axis::x, 60);
    const auto qm = rcm::to_quaternion(m);
    CHECK(rcm::quaternion_log_distance2(qm, about_x(M_PI / 3)) == Approx(0.0).epsilon(1e-9));
}

TEST_CASE("cluster: Eq. 5 adds the scaled height difference and the weighted rotation terms")
{
    rcm::pose a{1.0, {about_x(0), about_x(0)}}, b{3.0, {about_x(0.4), about_x(0.2)}};
    const std::vector<double> w{2.0, 0.5};
    CHECK(rcm::pose_distance(a, b, w, 1.0, 4.0) == Approx(0.5 + 2 * 0.04 + 0.5 * 0.01));
    CHECK(rcm::pose_distance(b, a, w, 1.0, 4.0) == Approx(rcm::pose_distance(a, b, w, 1.0, 4.0)));
}

TEST_CASE("cluster: the root's facing is discarded, its tilt is kept")
{
    auto c = clip::make(chain(), 3, 30);
    c.angle(1, 0, 1) = 90;    // frame 1: root turned about the up axis (y)
    c.angle(2, 0, 0) = 30;    // frame 2: root tilted about x
    c.position(1, 0, 0) = 50;  // and moved on the ground plane
    const auto r = rcm::find_roles(c.skel);
    const auto poses = rcm::clip_poses(c, r);
    const auto w = rcm::pose_weights(c.skel, r);
    CHECK(w[0] == Approx(2.0));
    CHECK(rcm::pose_distance(poses[0], poses[1], w, 1.0, 1.0) == Approx(0.0).epsilon(1e-9));
    CHECK(rcm::pose_distance(poses[0], poses[2], w, 1.0, 1.0) == Approx(2.0 * std::pow(M_PI / 12, 2)));
}

TEST_CASE("cluster: average linkage separates separable groups")
{
    // points on a line in three well separated groups
    const std::vector<double> x{0, 0.1, 0.2, 10, 10.3, 10.1, 20, 20.2, 0.05};
    const std::size_t n = x.size();
    std::vector<double> d(n * n);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) d[i * n + j] = std::abs(x[i] - x[j]);
    const auto l = rcm::average_linkage(d, n, 3);
    CHECK(l[0] == l[1]);
    CHECK(l[0] == l[2]);
    CHECK(l[0] == l[8]);
    CHECK(l[3] == l[4]);
    CHECK(l[3] == l[5]);
    CHECK(l[6] == l[7]);
    CHECK(l[0] != l[3]);
    CHECK(l[3] != l[6]);
    CHECK(l[0] != l[6]);
    CHECK(rcm::average_linkage(d, n, n) == std::vector<std::size_t>{0, 1, 2, 3, 4, 5, 6, 7, 8});
    CHECK_THROWS_AS(rcm::average_linkage(d, n, 0), value_error);
}

TEST_CASE("cluster: poses in two stances form two clusters; medoids assign new poses")
{
    std::vector<rcm::pose> poses;
    for (int i = 0; i < 40; ++i) {
        const double jitter = 0.01 * (i % 5);
        if (i % 2) poses.push_back({100.0 + jitter, {about_x(0), about_x(1.2 + jitter)}});  // standing, arm up
        else poses.push_back({40.0 - jitter, {about_x(0.1), about_x(jitter)}});              // crouching, arm down
    }
    rcm::pose_cluster_options o;
    o.clusters = 2;
    const auto pc = rcm::cluster_poses(poses, {2.0, 2.0}, o);
    REQUIRE(pc.count() == 2);
    CHECK(pc.sizes[0] == 20);
    CHECK(pc.sizes[1] == 20);
    const auto up = pc.assign({98.0, {about_x(0), about_x(1.1)}});
    const auto down = pc.assign({42.0, {about_x(0.1), about_x(0.05)}});
    CHECK(up != down);
    CHECK(up == pc.assign(poses[1]));
    CHECK(down == pc.assign(poses[0]));
    CHECK_THROWS_AS(rcm::cluster_poses(std::vector<rcm::pose>(1, poses[0]), {1.0, 1.0}, o), value_error);
}
