#include "helpers.hpp"

#include <doctest/doctest.h>
#include <handemo/metrics/classifier.hpp>
#include <handemo/motion/keyframes.hpp>

#include <cmath>
#include <string>
#include <vector>

using namespace handemo;
using namespace handemo::metrics;

namespace {

// A deterministic pseudo-noise in [-1, 1].
double noise(std::size_t i) { return std::sin(12.9898 * static_cast<double>(i) + 78.233 * std::sin(static_cast<double>(i))); }

}  // namespace

TEST_CASE("nearest centroid separates separable classes despite a large within-class nuisance")
{
    // 3 classes along feature 1 (0, 3, 6); feature 0 is a nuisance spread over +-20 in every class (like
    // content); feature 2 is small noise
    std::vector<std::vector<double>> x;
    std::vector<std::string> y;
    const std::string names[] = {"a", "b", "c"};
    for (std::size_t i = 0; i < 60; ++i) {
        const std::size_t c = i % 3;
        x.push_back({20 * noise(i), 3.0 * static_cast<double>(c) + 0.3 * noise(i + 1000), noise(i + 2000)});
        y.push_back(names[c]);
    }
    for (double a : {0.0, 0.5, 1.0}) {
        nearest_centroid_classifier clf;
        clf.fit(x, y, a);
        CHECK(clf.classes() == std::vector<std::string>{"a", "b", "c"});
        int ok = 0;
        for (std::size_t i = 0; i < 30; ++i) {
            const std::size_t c = i % 3;
            const std::vector<double> q{20 * noise(i + 500), 3.0 * static_cast<double>(c) + 0.3 * noise(i + 1500), noise(i + 2500)};
            ok += clf.predict(q) == names[c];
        }
        CHECK(ok == 30);
    }
    // plain Euclidean distance on raw features would be dominated by the nuisance: check the metric matters
    int euclid_ok = 0;
    for (std::size_t i = 0; i < 30; ++i) {
        const std::size_t c = i % 3;
        const double q0 = 20 * noise(i + 500), q1 = 3.0 * static_cast<double>(c) + 0.3 * noise(i + 1500);
        double best = 1e300;
        std::size_t arg = 0;
        for (std::size_t n = 0; n < x.size(); ++n) {
            const double d = (x[n][0] - q0) * (x[n][0] - q0) + (x[n][1] - q1) * (x[n][1] - q1);
            if (d < best) best = d, arg = n;
        }
        euclid_ok += y[arg] == names[c];
    }
    CHECK(euclid_ok < 30);
}

TEST_CASE("nearest centroid posterior: the linear-discriminant reading of its distances")
{
    std::vector<std::vector<double>> x;
    std::vector<std::string> y;
    const std::string names[] = {"a", "b", "c"};
    for (std::size_t i = 0; i < 60; ++i) {
        const std::size_t c = i % 3;
        x.push_back({20 * noise(i), 3.0 * static_cast<double>(c) + 0.9 * noise(i + 1000), noise(i + 2000)});
        y.push_back(names[c]);
    }
    nearest_centroid_classifier clf;
    clf.fit(x, y);
    for (std::size_t i = 0; i < 20; ++i) {
        const std::vector<double> q{20 * noise(i + 500), 1.5 * static_cast<double>(i % 5) + 0.3 * noise(i + 1500), noise(i + 2500)};
        const auto d = clf.distances(q);
        double z = 0, total = 0, best = -1;
        std::string arg;
        for (double v : d) z += std::exp(-0.5 * v);
        for (std::size_t c = 0; c < 3; ++c) {
            const double p = clf.posterior(q, names[c]);
            CHECK(p == doctest::Approx(std::exp(-0.5 * d[c]) / z).epsilon(1e-12));  // exp(-d/2) / sum
            total += p;
            if (p > best) best = p, arg = names[c];
        }
        CHECK(total == doctest::Approx(1.0).epsilon(1e-12));
        CHECK(arg == clf.predict(q));  // the most probable class is the nearest one
    }
    // far from every centroid (distances ~1e4, exp underflows without the shift) it stays a probability
    const std::vector<double> far{0.0, 300.0, 0.0};
    CHECK(clf.posterior(far, "c") == doctest::Approx(1.0).epsilon(1e-9));
    CHECK(clf.posterior(far, "a") >= 0.0);
    CHECK(clf.posterior(far, "no such class") == 0.0);
}

TEST_CASE("nearest centroid: bad input is refused")
{
    nearest_centroid_classifier clf;
    CHECK_THROWS_AS(clf.predict({1.0}), value_error);
    CHECK_THROWS_AS(clf.fit({{1.0}, {2.0}}, {"a", "a"}), value_error);
    CHECK_THROWS_AS(clf.fit({{1.0}, {2.0, 3.0}}, {"a", "b"}), shape_error);
    CHECK_THROWS_AS(clf.fit({{1.0}, {2.0}}, {"a", "b"}, 1.5), value_error);
    clf.fit({{1.0}, {2.0}}, {"a", "b"});
    CHECK(clf.predict({0.9}) == "a");
    CHECK(clf.predict({2.5}) == "b");
    CHECK_THROWS_AS(clf.predict({1.0, 2.0}), shape_error);
}

TEST_CASE("motion features of keyframes")
{
    const clip a = handemo::metrics::test::sine_clip(81, 40, 10);
    const auto kf = extract_keyframes<9>(a);
    const auto f = motion_features(kf, a.duration());
    REQUIRE(f.size() == 4 * 23 + 3);
    CHECK(f[4 * 23 + 2] == doctest::Approx(std::log(a.duration())));
    // doubling the duration lowers only the speed feature (by log-ish amounts) and the duration feature
    const auto g = motion_features(kf, 2 * a.duration());
    for (std::size_t i = 0; i < 4 * 23 + 1; ++i) CHECK(g[i] == f[i]);
    CHECK(g[4 * 23 + 1] < f[4 * 23 + 1]);
    CHECK_THROWS_AS(motion_features(kf, 0.0), value_error);
}
