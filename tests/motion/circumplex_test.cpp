// The circumplex interpolation (motion/circumplex.hpp): weights that sum to one, are never negative, are exact at
// every label, linear along lines from neutral to a label, barycentric inside the labels' fan, and Lipschitz; the
// points and label tables it refuses; curve files and paths over a duration.
#include <handemo/motion/circumplex.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace handemo;

namespace {

/// The shipped table's labels of one data set, neutral first.
std::vector<label_point> circumplex_labels_of(const std::vector<std::string>& names)
{
    const auto t = load_circumplex(std::string(HANDEMO_SOURCE_DIR) + "/data/rcm/circumplex.json");
    std::vector<label_point> out;
    for (const auto& n : names) out.push_back(t.at(n));
    return out;
}

const std::vector<std::string> circumplex_hand = {"neutral", "angry", "happy", "sad", "fearful"};
const std::vector<std::string> circumplex_body = {"normal", "active", "angry", "happy", "not-confident", "proud", "sad", "tired"};

}  // namespace

TEST_CASE("circumplex interpolation: weights sum to one, never negative, exact at the labels")
{
    for (const auto& names : {circumplex_hand, circumplex_body}) {
        const circumplex_interpolation ip(circumplex_labels_of(names), 0);
        // exactly one-hot at every label's own point
        for (std::size_t l = 0; l < names.size(); ++l) {
            CAPTURE(names[l]);
            const auto w = ip.weights(ip.labels()[l].valence, ip.labels()[l].arousal);
            for (std::size_t i = 0; i < w.size(); ++i) CHECK(w[i] == (i == l ? 1.0 : 0.0));
        }
        // a point a hair from a label's (coordinates typed as decimals, rounded) is the label's, exactly
        const auto& l1 = ip.labels()[1];
        const auto near = ip.weights(l1.valence + 1e-12, l1.arousal - 1e-12);
        CHECK(near[1] == 1.0);
        CHECK(near[0] == 0.0);
        // a partition of unity over the disc
        std::mt19937 rng(3);
        std::uniform_real_distribution<double> u(-1, 1);
        for (int n = 0; n < 2000; ++n) {
            const double v = u(rng), a = u(rng);
            if (v * v + a * a > 1) continue;
            const auto w = ip.weights(v, a);
            double sum = 0;
            std::size_t nonzero = 0;
            for (double x : w) {
                CHECK(x >= 0);
                sum += x;
                nonzero += x != 0;
            }
            CHECK(sum == doctest::Approx(1.0).epsilon(1e-12));
            CHECK(nonzero <= 3);  // neutral and the two labels bracketing the direction
        }
    }
}

TEST_CASE("circumplex interpolation: linear from neutral to each label, barycentric inside the fan")
{
    const auto labels = circumplex_labels_of(circumplex_hand);
    const circumplex_interpolation ip(labels, 0);
    const auto& n = labels[0];
    for (std::size_t l = 1; l < labels.size(); ++l)
        for (int s = 1; s < 10; ++s) {
            const double t = s / 10.0;
            const auto w = ip.weights(n.valence + t * (labels[l].valence - n.valence), n.arousal + t * (labels[l].arousal - n.arousal));
            CHECK(w[l] == doctest::Approx(t).epsilon(1e-9));
            CHECK(w[0] == doctest::Approx(1 - t).epsilon(1e-9));
        }
    // inside the triangle (neutral, happy, angry): the weights reproduce the point (linear precision)
    for (double f : {0.2, 0.5, 0.8}) {
        const double v = n.valence + f * (0.5 * labels[1].valence + 0.5 * labels[2].valence - n.valence);
        const double a = n.arousal + f * (0.5 * labels[1].arousal + 0.5 * labels[2].arousal - n.arousal);
        const auto w = ip.weights(v, a);
        double pv = 0, pa = 0;
        for (std::size_t i = 0; i < w.size(); ++i) pv += w[i] * labels[i].valence, pa += w[i] * labels[i].arousal;
        CHECK(pv == doctest::Approx(v).epsilon(1e-12));
        CHECK(pa == doctest::Approx(a).epsilon(1e-12));
        CHECK(w[1] == doctest::Approx(w[2]).epsilon(1e-9));
    }
    // beyond a label (further along its line) the blend stays the label's: no extrapolation
    const auto& h = labels[2];
    const auto w = ip.weights(h.valence / std::hypot(h.valence, h.arousal) * 0.999, h.arousal / std::hypot(h.valence, h.arousal) * 0.999);
    CHECK(w[0] == 0.0);
}

TEST_CASE("circumplex interpolation: Lipschitz over the disc (no jump between neighbouring points)")
{
    for (const auto& names : {circumplex_hand, circumplex_body}) {
        const circumplex_interpolation ip(circumplex_labels_of(names), 0);
        std::mt19937 rng(8);
        std::uniform_real_distribution<double> u(-1, 1);
        double coarse = 0, fine = 0;
        for (int n = 0; n < 3000; ++n) {
            const double v = u(rng), a = u(rng), dv = u(rng), da = u(rng);
            for (double h : {1e-2, 1e-5}) {
                const double v2 = v + h * dv, a2 = a + h * da;
                if (v * v + a * a > 1 || v2 * v2 + a2 * a2 > 1) continue;
                const auto w = ip.weights(v, a), w2 = ip.weights(v2, a2);
                double l1 = 0;
                for (std::size_t i = 0; i < w.size(); ++i) l1 += std::abs(w[i] - w2[i]);
                (h > 1e-3 ? coarse : fine) = std::max(h > 1e-3 ? coarse : fine, l1 / std::hypot(v - v2, a - a2));
            }
        }
        // a discontinuity would make the ratio grow as the step shrinks (1e3 times from 1e-2 to 1e-5)
        CHECK(fine < 2 * coarse + 1);
        CHECK(coarse < 60);
        MESSAGE(names[0] << " labels: the weights' L1 change per unit distance up to " << coarse);
    }
}

TEST_CASE("circumplex interpolation: refused points and label sets")
{
    const auto labels = circumplex_labels_of(circumplex_hand);
    const circumplex_interpolation ip(labels, 0);
    CHECK_THROWS_WITH_AS(ip.weights(0.9, 0.9), doctest::Contains("(valence 0.9, arousal 0.9) lies outside the circumplex"), value_error);
    CHECK_THROWS_AS(ip.weights(std::nan(""), 0), value_error);
    CHECK_NOTHROW(ip.weights(1, 0));  // the circle itself is in
    auto on_neutral = labels;
    on_neutral[1].valence = labels[0].valence, on_neutral[1].arousal = labels[0].arousal;
    CHECK_THROWS_WITH_AS(circumplex_interpolation(on_neutral, 0), doctest::Contains("'angry' sits on neutral's point"), value_error);
    auto one_ray = labels;  // happy halfway to a copy of it on the same ray
    one_ray[3].valence = labels[0].valence + 0.5 * (labels[2].valence - labels[0].valence);
    one_ray[3].arousal = labels[0].arousal + 0.5 * (labels[2].arousal - labels[0].arousal);
    CHECK_THROWS_WITH_AS(circumplex_interpolation(one_ray, 0), doctest::Contains("lie on one ray from neutral"), value_error);
    CHECK_THROWS_AS(circumplex_interpolation({labels[0]}, 0), value_error);
    // one label and neutral: the label's weight grows with the distance from neutral in every direction
    const circumplex_interpolation two({labels[0], labels[3]}, 0);
    const auto w = two.weights(0.5, 0.5);
    CHECK(w[0] + w[1] == doctest::Approx(1.0));
    CHECK(w[1] > 0);
}

TEST_CASE("circumplex curves: files of time,valence,arousal rows, paths over a duration")
{
    const auto c = parse_va_curve("time,valence,arousal\n# a comment\n0,0.1,-0.4\n\n1.5, -0.6, 0.3\r\n3,0,0\n", "c.csv");
    REQUIRE(c.size() == 3);
    CHECK(c.at(-1).first == doctest::Approx(0.1));
    CHECK(c.at(0.75).first == doctest::Approx(-0.25));
    CHECK(c.at(0.75).second == doctest::Approx(-0.05));
    CHECK(c.at(9).second == doctest::Approx(0.0));
    CHECK_THROWS_WITH_AS(parse_va_curve("0,0,0\n1,0.9,0.9\n", "c.csv"), doctest::Contains("c.csv: line 2: the point (valence 0.9, arousal 0.9) lies outside"),
                         format_error);
    CHECK_THROWS_WITH_AS(parse_va_curve("0,0,0\n1,0,x\n", "c.csv"), doctest::Contains("c.csv: line 2: expected three numbers"), format_error);
    CHECK_THROWS_WITH_AS(parse_va_curve("0,0,0\n1,0\n", "c.csv"), doctest::Contains("c.csv: line 2: expected three numbers"), format_error);
    CHECK_THROWS_WITH_AS(parse_va_curve("0,0,0\n\n0,0.1,0\n", "c.csv"), doctest::Contains("c.csv: line 3: time 0 is not after"), format_error);
    CHECK_THROWS_WITH_AS(parse_va_curve("# nothing\n", "c.csv"), doctest::Contains("c.csv: no rows"), format_error);
    CHECK_THROWS_AS(read_va_curve("/nonexistent/curve.csv"), io_error);

    const auto labels = circumplex_labels_of(circumplex_hand);
    const auto p = path_curve(parse_path("neutral,sad,0.5:0.5", labels), 4.0);
    REQUIRE(p.size() == 3);
    CHECK(p.time[1] == doctest::Approx(2.0));
    CHECK(p.at(4.0).first == doctest::Approx(0.5));
    CHECK_THROWS_WITH_AS(path_curve(parse_path("neutral,0.9:0.9", labels), 1.0), doctest::Contains("waypoint '0.9:0.9'"), value_error);
    CHECK_THROWS_WITH_AS(parse_path("neutral,bored", labels, "transfer: --path"), doctest::Contains("transfer: --path: waypoint 'bored' is not a label"),
                         value_error);
    CHECK_THROWS_AS(path_curve(parse_path("sad", labels), 0.0), value_error);
}
