// Section 3.2: effective (std across emotions >= 0.21 for a majority of performers) and consistent (std
// across performers <= 0.2 for a majority of emotions) features.
#include <handemo/rcm.hpp>

#include <doctest/doctest.h>

using namespace handemo;

namespace {

/// 3 performers x 3 emotions, one clip each; columns:
/// 0 effective and consistent (emotion * 0.4), 1 constant, 2 performer * 0.4 (not effective),
/// 3 emotion * 0.4 plus a large performer term (effective, not consistent), 4 emotion * 0.2 (std 0.163:
/// just below the effectiveness threshold), 5 emotion * 0.26 (std 0.212: just above).
struct toy {
    rcm::matrix x = xt::zeros<double>({std::size_t{9}, std::size_t{6}});
    std::vector<std::string> emo, perf;
    toy()
    {
        const char* en[] = {"sad", "happy", "angry"};
        for (std::size_t p = 0; p < 3; ++p)
            for (std::size_t e = 0; e < 3; ++e) {
                const std::size_t i = p * 3 + e;
                const double E = static_cast<double>(e), P = static_cast<double>(p);
                x(i, 0) = 0.4 * E;
                x(i, 1) = 0.5;
                x(i, 2) = 0.4 * P;
                x(i, 3) = 0.4 * E + 0.5 * P;
                x(i, 4) = 0.2 * E;
                x(i, 5) = 0.26 * E;
                emo.push_back(en[e]);
                perf.push_back("performer" + std::to_string(p));
            }
    }
};

}  // namespace

TEST_CASE("selection: the paper's thresholds")
{
    toy t;
    rcm::selection_options o;
    o.min_features = 0;
    const auto r = rcm::select_features(t.x, t.emo, t.perf, o);
    CHECK(r.need_effective == 3);   // ceil(7/9 * 3)
    CHECK(r.need_consistent == 3);  // ceil(10/12 * 3)
    CHECK(r.selected == std::vector<std::size_t>{0, 5});
    CHECK(r.survivors == 2);
    CHECK_FALSE(r.fallback);
    CHECK(r.effective_count == std::vector<std::size_t>{3, 0, 0, 3, 0, 3});
    CHECK(r.consistent_count == std::vector<std::size_t>{3, 3, 0, 0, 3, 3});
}

TEST_CASE("selection: majorities of nine performers and twelve emotions are 7 and 10")
{
    rcm::matrix x = xt::zeros<double>({std::size_t{108}, std::size_t{1}});
    std::vector<std::string> e, p;
    for (std::size_t i = 0; i < 108; ++i) {
        x(i, 0) = static_cast<double>(i % 12) / 11.0;
        e.push_back("e" + std::to_string(i % 12));
        p.push_back("p" + std::to_string(i / 12));
    }
    const auto r = rcm::select_features(x, e, p);
    CHECK(r.need_effective == 7);
    CHECK(r.need_consistent == 10);
    CHECK(r.selected == std::vector<std::size_t>{0});
}

TEST_CASE("selection: fallback fills up with the features closest to passing")
{
    toy t;
    rcm::selection_options o;
    o.effective_std = 0.5;  // nothing is effective now
    o.min_features = 2;
    const auto r = rcm::select_features(t.x, t.emo, t.perf, o);
    CHECK(r.survivors == 0);
    CHECK(r.fallback);
    CHECK(r.selected.size() == 2);
    // 0 and 5 are consistent everywhere and the most effective of those
    CHECK(r.selected == std::vector<std::size_t>{0, 5});
}

TEST_CASE("selection: errors")
{
    toy t;
    CHECK_THROWS_AS(rcm::select_features(t.x, {"a"}, t.perf), shape_error);
    const std::vector<std::string> one(9, "happy");
    CHECK_THROWS_WITH_AS(rcm::select_features(t.x, one, t.perf), doctest::Contains("1 emotions"), value_error);
}
