#include <doctest/doctest.h>
#include <handemo/stargan/dataset.hpp>

#include "helpers.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <stdlib.h>

namespace fs = std::filesystem;
using namespace handemo;

TEST_CASE("parse_clip_name takes the last three fields")
{
    auto n = stargan::parse_clip_name("hand_hand-on-mouse_angry_3");
    CHECK(n.prefix == "hand");
    CHECK(n.content == "hand-on-mouse");
    CHECK(n.emotion == "angry");
    CHECK(n.take == "3");
    n = stargan::parse_clip_name("dataset-1_walk-back_not-confident_001");
    CHECK(n.prefix == "dataset-1");
    CHECK(n.content == "walk-back");
    CHECK(n.emotion == "not-confident");
    n = stargan::parse_clip_name("my_prefix_x_walk_sad_2");
    CHECK(n.prefix == "my_prefix_x");
    CHECK_THROWS_WITH_AS(stargan::parse_clip_name("walk_sad"), doctest::Contains("walk_sad"), value_error);
    CHECK_THROWS_AS(stargan::parse_clip_name("a__sad_1"), value_error);
}

TEST_CASE("manifest.csv labels clips and bad manifests are refused with the line")
{
    const fs::path dir = fs::temp_directory_path() / "handemo_manifest_test";
    fs::remove_all(dir);
    fs::create_directories(dir);
    clip c = clip::make(hand_skeleton(), 10, 30);
    write_bvh(dir / "a.bvh", c);
    c = clip::make(hand_skeleton(), 20, 30);
    write_bvh(dir / "b.bvh", c);
    write_file_atomic(dir / "manifest.csv", "path,content,emotion\na.bvh,wave,neutral\nb.bvh,wave,sad\n");
    auto d = stargan::load_folder(dir);
    REQUIRE(d.size() == 2);
    CHECK(d[0].emotion == "neutral");
    CHECK(d[1].emotion == "sad");
    const auto tempo = stargan::tempo_factors(d, {"neutral", "sad", "happy"}, "neutral");
    CHECK(tempo[0] == doctest::Approx(1.0));
    CHECK(tempo[1] == doctest::Approx(2.0));
    CHECK(tempo[2] == doctest::Approx(1.0));  // no data: unchanged
    write_file_atomic(dir / "manifest.csv", "path,content,emotion\na.bvh,wave\n");
    CHECK_THROWS_WITH_AS(stargan::load_folder(dir), doctest::Contains("manifest.csv:2"), format_error);
    fs::remove_all(dir);
}

TEST_CASE("load_folder names a path whose status cannot be read (io_error, not std::filesystem::filesystem_error)")
{
    std::string t = (fs::temp_directory_path() / "handemo_load_folder_XXXXXX").string();
    REQUIRE(::mkdtemp(t.data()) != nullptr);
    const fs::path dir = t;
    const fs::path loop = dir / "loop";
    fs::create_symlink(loop, loop);  // a link to itself: stat fails with ELOOP
    CHECK_THROWS_WITH_AS(stargan::load_folder(loop), doctest::Contains(loop.string().c_str()), io_error);
    CHECK_THROWS_WITH_AS(stargan::load_folder(dir), doctest::Contains(loop.string().c_str()), io_error);  // an entry
    fs::remove(loop);
    const fs::path manifest = dir / "manifest.csv";
    fs::create_symlink(manifest, manifest);
    CHECK_THROWS_WITH_AS(stargan::load_folder(dir), doctest::Contains(manifest.string().c_str()), io_error);
    fs::remove_all(dir);
}

TEST_CASE("manifest.csv: duplicate rows, ../ and absolute paths are refused, naming the line")
{
    const std::string m = "data/manifest.csv";
    auto refused = [&](const std::string& rows, const std::string& expected) {
        CHECK_THROWS_WITH_AS(stargan::parse_manifest("path,content,emotion\n" + rows, "data", m),
                             doctest::Contains(expected.c_str()), format_error);
    };
    refused("a.bvh,wave,neutral\nb.bvh,wave,sad\na.bvh,wave,sad\n",
            "data/manifest.csv:4: path 'a.bvh' is listed twice (first on line 2)");
    refused("a.bvh,wave,neutral\n./sub/../a.bvh,wave,sad\n", "data/manifest.csv:3: path './sub/../a.bvh' leaves the data folder");
    refused("sub/./x.bvh,wave,neutral\nsub/x.bvh,wave,sad\n", "data/manifest.csv:3: path 'sub/x.bvh' is listed twice (first on line 2)");
    refused("../secret.bvh,wave,neutral\n", "data/manifest.csv:2: path '../secret.bvh' leaves the data folder (..)");
    refused("a/../../b.bvh,wave,neutral\n", "data/manifest.csv:2: path 'a/../../b.bvh' leaves the data folder");
    refused("/etc/passwd,wave,neutral\n", "data/manifest.csv:2: path '/etc/passwd' is absolute");
    const auto ok = stargan::parse_manifest("path,content,emotion\nsub/a.bvh,wave,neutral\n", "data", m);
    REQUIRE(ok.size() == 1);
    CHECK(ok[0].path == fs::path("data") / "sub/a.bvh");
}

using namespace handemo::test;

TEST_CASE("tempo_fit recovers consistent duration ratios and prefers the simplest exact estimator")
{
    const std::vector<std::string> domains{"neutral", "slow", "fast"};
    std::vector<handemo::labelled_clip> d;
    const double neutral_seconds[] = {2.0, 3.0, 4.0, 5.0};
    for (int i = 0; i < 4; ++i) {
        const std::string content = "c" + std::to_string(i);
        d.push_back(timed_clip(content, "neutral", neutral_seconds[i]));
        d.push_back(timed_clip(content, "slow", 1.5 * neutral_seconds[i]));
        d.push_back(timed_clip(content, "fast", 0.5 * neutral_seconds[i]));
    }
    const auto r = stargan::tempo_fit(d, domains, "neutral");
    CHECK(r.cv_contents == 4);
    CHECK(r.pairs == 8);
    REQUIRE(r.candidates.size() == stargan::tempo_estimator_count);
    for (const auto& c : r.candidates) {
        CAPTURE(stargan::to_string(c.estimator));
        if (c.estimator == stargan::tempo_estimator::keep) {
            CHECK(c.cv_error == doctest::Approx(0.5 * (std::log(1.5) + std::log(2.0))));
            continue;
        }
        CHECK(c.factors[1] == doctest::Approx(1.5));
        CHECK(c.factors[2] == doctest::Approx(0.5));
        CHECK(c.cv_error == doctest::Approx(0.0).epsilon(1e-9));
    }
    CHECK(r.estimator == stargan::tempo_estimator::median);  // every estimator but keep is exact: the simplest wins
    CHECK(r.factors == std::vector<double>{1.0, 1.5, 0.5});
    CHECK(stargan::tempo_factors(d, domains, "neutral") == r.factors);
}

TEST_CASE("tempo basis: the cadence learns the tempo when takes hold different numbers of cycles")
{
    const std::vector<std::string> domains{"neutral", "slow", "fast"};
    // four contents of periods 1.0-1.6 s; "slow" moves 1.5x slower than neutral, "fast" twice as fast
    const auto set_of = [](double neutral_cycles, double emotion_cycles) {
        std::vector<handemo::labelled_clip> d;
        for (int i = 0; i < 4; ++i) {
            const std::string content = "c" + std::to_string(i);
            const double period = 1.0 + 0.2 * i;
            d.push_back(cycling_clip(content, "neutral", period, neutral_cycles));
            d.push_back(cycling_clip(content, "slow", 1.5 * period, emotion_cycles));
            d.push_back(cycling_clip(content, "fast", 0.5 * period, emotion_cycles));
        }
        return d;
    };
    // every take two cycles: the durations and the cadences say the same
    const auto same = set_of(2, 2);
    const auto agree = stargan::tempo_basis_check(same, domains, "neutral");
    CHECK(agree.pairs == 8);
    CHECK(agree.disagreement < 0.03);
    CHECK(agree.basis == stargan::tempo_basis::duration);
    const auto by_duration = stargan::tempo_fit(same, domains, "neutral");
    const auto automatic = stargan::tempo_fit(same, domains, "neutral", false, stargan::tempo_basis::automatic);
    CHECK(automatic.basis.basis == stargan::tempo_basis::duration);
    CHECK(automatic.factors == by_duration.factors);  // the same numbers as before the option existed
    CHECK(std::isnan(by_duration.basis.disagreement));
    CHECK(by_duration.factors[1] == doctest::Approx(1.5).epsilon(0.02));

    // the neutral takes are one-cycle fragments, the emotional ones four cycles: the durations count cycles
    const auto cut = set_of(1, 4);
    const auto disagree = stargan::tempo_basis_check(cut, domains, "neutral");
    CHECK(disagree.basis == stargan::tempo_basis::cadence);
    CHECK(disagree.disagreement == doctest::Approx(std::log(4.0)).epsilon(0.03));
    const auto durations = stargan::tempo_fit(cut, domains, "neutral");
    CHECK(durations.factors[1] == doctest::Approx(6.0).epsilon(0.02));  // 4 cycles x 1.5 against 1 cycle
    const auto cadences = stargan::tempo_fit(cut, domains, "neutral", false, stargan::tempo_basis::cadence);
    CHECK(cadences.basis.basis == stargan::tempo_basis::cadence);
    CHECK(cadences.factors[1] == doctest::Approx(1.5).epsilon(0.03));
    CHECK(cadences.factors[2] == doctest::Approx(0.5).epsilon(0.03));
    const auto chosen = stargan::tempo_fit(cut, domains, "neutral", true, stargan::tempo_basis::automatic);
    CHECK(chosen.basis.basis == stargan::tempo_basis::cadence);
    CHECK(chosen.factors[1] == doctest::Approx(1.5).epsilon(0.03));
    CHECK(stargan::tempo_factors(cut, domains, "neutral", false, stargan::tempo_basis::automatic) ==
          stargan::tempo_fit(cut, domains, "neutral", false, stargan::tempo_basis::cadence).factors);

    CHECK(stargan::parse_tempo_basis("auto") == stargan::tempo_basis::automatic);
    CHECK_THROWS_WITH_AS(stargan::parse_tempo_basis("tempo", "train: tempo_basis"),
                         doctest::Contains("train: tempo_basis 'tempo' is not duration, cadence or auto"), value_error);
    stargan::train_options o;
    o.tempo_basis = "cadences";
    CHECK_THROWS_WITH_AS(o.validate(), doctest::Contains("tempo_basis 'cadences'"), value_error);
    o.tempo_basis = "auto";
    CHECK(o.to_json().at("tempo_basis") == "auto");
    o.tempo_basis = "duration";
    CHECK_FALSE(o.to_json().contains("tempo_basis"));  // older checkpoints' options stay equal
}

TEST_CASE("tempo_fit does not blow up when one content's neutral capture is truncated")
{
    // Bandai's dash/run/walk-back neutrals are 20-31 frame fragments: the per-take ratio becomes 4-13x while the
    // other contents agree on 1.5x. Here one of five contents has its neutral cut to a sixth.
    const std::vector<std::string> domains{"neutral", "slow"};
    std::vector<handemo::labelled_clip> d;
    for (int i = 0; i < 5; ++i) {
        const std::string content = "c" + std::to_string(i);
        const double n = 2.0 + i;
        d.push_back(timed_clip(content, "neutral", i == 0 ? n / 6 : n));
        d.push_back(timed_clip(content, "slow", 1.5 * n));
    }
    const auto r = stargan::tempo_fit(d, domains, "neutral");
    INFO("chosen " << stargan::to_string(r.estimator) << ", factor " << r.factors[1]);
    CHECK(r.factors[0] == 1.0);
    CHECK(r.factors[1] > 1.5 / 1.1);  // within 10% of the four agreeing contents, far from the truncated 9x
    CHECK(r.factors[1] < 1.5 * 1.1);
    CHECK(r.estimator != stargan::tempo_estimator::keep);
    // the median ignores the truncated take entirely
    CHECK(stargan::tempo_estimate(stargan::tempo_estimator::median, d, domains, "neutral")[1] == doctest::Approx(1.5));
}

TEST_CASE("tempo_fit keeps the duration when contents disagree on the direction of the change")
{
    // "x" doubles the duration of c0 and c2 and halves that of c1 and c3: no factor predicts a left-out content.
    const std::vector<std::string> domains{"neutral", "x"};
    std::vector<handemo::labelled_clip> d;
    for (int i = 0; i < 4; ++i) {
        const std::string content = "c" + std::to_string(i);
        d.push_back(timed_clip(content, "neutral", 2.0));
        d.push_back(timed_clip(content, "x", i % 2 ? 1.0 : 4.0));
    }
    const auto r = stargan::tempo_fit(d, domains, "neutral");
    CHECK(r.estimator == stargan::tempo_estimator::keep);
    CHECK(r.factors == std::vector<double>{1.0, 1.0});
    CHECK(cv_error_of(r, stargan::tempo_estimator::keep) == doctest::Approx(std::log(2.0)));
    for (const auto& c : r.candidates)
        if (c.estimator != stargan::tempo_estimator::keep) CHECK(c.cv_error > std::log(2.0));
}

TEST_CASE("tempo_fit without a second content uses the duration-weighted ratio and reports no CV error")
{
    const std::vector<std::string> domains{"neutral", "slow"};
    const std::vector<handemo::labelled_clip> d{timed_clip("a", "neutral", 2.0, "0"), timed_clip("a", "slow", 6.0, "0"),
                                                timed_clip("a", "neutral", 4.0, "1"), timed_clip("a", "slow", 6.0, "1")};
    const auto r = stargan::tempo_fit(d, domains, "neutral");
    CHECK(r.cv_contents == 0);
    CHECK(r.estimator == stargan::tempo_estimator::weighted);
    CHECK(r.factors[1] == doctest::Approx(12.0 / 6.0));
    for (const auto& c : r.candidates) CHECK(std::isnan(c.cv_error));
}

TEST_CASE("tempo shrink: factors no left-out content follows are shrunk to 1, factors every content follows are kept")
{
    const std::vector<std::string> domains{"neutral", "sad", "fast"};
    const auto half = stargan::shrink_tempo({1.0, 4.0, 0.25}, 0.5);  // half-way in log space: the square root
    CHECK(half[0] == 1.0);
    CHECK(half[1] == doctest::Approx(2.0));
    CHECK(half[2] == doctest::Approx(0.5));
    CHECK(stargan::shrink_tempo({1.0, 4.0, 0.25}, 1.0) == std::vector<double>{1.0, 1.0, 1.0});
    CHECK(stargan::shrink_tempo({1.0, 4.0, 0.25}, 0.0) == std::vector<double>{1.0, 4.0, 0.25});
    const auto& grid = stargan::tempo_shrink_grid;
    REQUIRE(grid.size() == 5);
    SUBCASE("contents disagree: each left-out content goes the other way, so full shrinkage wins")
    {
        // sad lasts 2x neutral on content a and 0.5x on b: fitted on one, the other is predicted the wrong way
        std::vector<handemo::labelled_clip> d{timed_clip("a", "neutral", 2.0), timed_clip("a", "sad", 4.0),
                                              timed_clip("b", "neutral", 2.0), timed_clip("b", "sad", 1.0)};
        const auto c = stargan::tempo_shrink_fit(d, domains, "neutral", stargan::tempo_estimator::weighted);
        CHECK(c.contents == 2);
        REQUIRE(c.errors.size() == grid.size());
        // left-out error |(1 - w) log 0.5 - log 2| = (2 - w) log 2 on either content
        for (std::size_t w = 0; w < grid.size(); ++w) CHECK(c.errors[w] == doctest::Approx((2.0 - grid[w]) * std::log(2.0)));
        CHECK(c.weight == 1.0);
    }
    SUBCASE("contents agree: the factors predict every left-out content exactly, so no shrinkage")
    {
        std::vector<handemo::labelled_clip> d;
        for (const char* content : {"a", "b", "c"})
            for (double n : {2.0, 3.0}) {
                const std::string take = n == 2.0 ? "0" : "1";
                d.push_back(timed_clip(content, "neutral", n, take));
                d.push_back(timed_clip(content, "sad", 2.0 * n, take));
                d.push_back(timed_clip(content, "fast", 0.5 * n, take));
            }
        const auto c = stargan::tempo_shrink_fit(d, domains, "neutral", stargan::tempo_estimator::median);
        CHECK(c.contents == 3);
        // left-out error over the sad and fast pairs: (w log 2 + w log 2) / 2
        for (std::size_t w = 0; w < grid.size(); ++w) CHECK(c.errors[w] == doctest::Approx(grid[w] * std::log(2.0)).epsilon(1e-9));
        CHECK(c.weight == 0.0);
        // tempo_fit with shrinking: the check's weight is recorded, the factors are unchanged
        const auto r = stargan::tempo_fit(d, domains, "neutral", true);
        CHECK(r.shrink_weight == 0.0);
        CHECK(r.shrink_errors == c.errors);
        CHECK(r.factors == stargan::tempo_fit(d, domains, "neutral").factors);
    }
    SUBCASE("no change to shrink: every weight scores the same and the tie goes to no shrinkage")
    {
        std::vector<handemo::labelled_clip> d{timed_clip("a", "neutral", 2.0), timed_clip("a", "sad", 2.0),
                                              timed_clip("b", "neutral", 3.0), timed_clip("b", "sad", 3.0)};
        const auto c = stargan::tempo_shrink_fit(d, domains, "neutral", stargan::tempo_estimator::weighted);
        for (double e : c.errors) CHECK(e == doctest::Approx(0.0));
        CHECK(c.weight == 0.0);
    }
    SUBCASE("one content: no check, no shrinkage")
    {
        std::vector<handemo::labelled_clip> d{timed_clip("a", "neutral", 2.0), timed_clip("a", "sad", 4.0)};
        const auto c = stargan::tempo_shrink_fit(d, domains, "neutral", stargan::tempo_estimator::weighted);
        CHECK(c.contents == 0);
        CHECK(c.weight == 0.0);
        CHECK(std::isnan(c.errors[0]));
        CHECK(stargan::tempo_factors(d, domains, "neutral", true) == stargan::tempo_factors(d, domains, "neutral"));
    }
}

TEST_CASE("tempo shrink through tempo_fit: a partly consistent set gets the weight its check chose, applied in log space")
{
    // sad: 3x on a, 3x on b, 1x on c (three contents, one of which does not slow down)
    const std::vector<std::string> domains{"neutral", "sad"};
    std::vector<handemo::labelled_clip> d{timed_clip("a", "neutral", 2.0), timed_clip("a", "sad", 6.0), timed_clip("b", "neutral", 2.0),
                                          timed_clip("b", "sad", 6.0),     timed_clip("c", "neutral", 2.0), timed_clip("c", "sad", 2.0)};
    const auto plain = stargan::tempo_fit(d, domains, "neutral");
    const auto r = stargan::tempo_fit(d, domains, "neutral", true);
    const auto c = stargan::tempo_shrink_fit(d, domains, "neutral", plain.estimator);
    CHECK(r.estimator == plain.estimator);
    CHECK(r.shrink_weight == c.weight);
    CHECK(r.factors == stargan::shrink_tempo(plain.factors, c.weight));
    CHECK(stargan::tempo_factors(d, domains, "neutral", true) == r.factors);
    std::size_t best = 0;
    for (std::size_t w = 0; w < c.errors.size(); ++w)
        if (c.errors[w] < c.errors[best] - 1e-12) best = w;
    CHECK(c.weight == stargan::tempo_shrink_grid[best]);
    MESSAGE("estimator " << stargan::to_string(plain.estimator) << ", factor " << plain.factors[1] << ", shrink weight " << c.weight);
}
