#include <doctest/doctest.h>
#include <handemo/motion/circumplex.hpp>
#include <handemo/stargan/continuous.hpp>
#include <handemo/stargan/tempo_neighbours.hpp>
#include <handemo/stargan/train.hpp>
#include <handemo/stargan/transfer.hpp>

#include "helpers.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

using namespace handemo;

namespace {

// Two kinds of content: gestures (neutral 2 s) that "sad" makes three times as long, and walks (neutral 6 s) whose
// sad takes last as long as the neutral ones. The clips are still, so their descriptors differ by duration alone.
std::vector<labelled_clip> two_kinds(int per_kind = 2)
{
    std::vector<labelled_clip> d;
    for (int i = 0; i < per_kind; ++i) {
        const std::string g = "gesture" + std::to_string(i), w = "walk" + std::to_string(i);
        d.push_back(timed_clip(g, "neutral", 2.0)), d.push_back(timed_clip(g, "sad", 6.0));
        d.push_back(timed_clip(w, "neutral", 6.0)), d.push_back(timed_clip(w, "sad", 6.0));
    }
    return d;
}

}  // namespace

TEST_CASE("tempo neighbours: contents of two kinds get their own kind's tempo, chosen by the leave-one-content-out check")
{
    const std::vector<std::string> domains{"neutral", "sad"};
    const auto d = two_kinds();
    const auto t = stargan::tempo_neighbours_fit(d, domains, "neutral");
    // left out, each content's nearest other content is of its kind: one neighbour predicts it exactly; two or three
    // mix in the other kind (log 3 / 2 and log 3 / 3 or 2 log 3 / 3 off), and so does any one factor for all
    REQUIRE(t.errors.size() == 1 + stargan::tempo_neighbour_grid.size());
    CHECK(t.errors.back() == doctest::Approx(0.0));
    CHECK(t.errors[0] > 0.3);
    CHECK(t.k == 1);
    CHECK(t.contents == std::vector<std::string>{"gesture0", "gesture1", "walk0", "walk1"});
    const std::vector<double> learned{1.0, 1.7};
    const auto gesture = t.factors(stargan::tempo_descriptor(timed_clip("new", "neutral", 2.2).motion), learned);
    const auto walk = t.factors(stargan::tempo_descriptor(timed_clip("new", "neutral", 5.5).motion), learned);
    CHECK(gesture[0] == doctest::Approx(1.0));
    CHECK(gesture[1] == doctest::Approx(3.0));
    CHECK(walk[1] == doctest::Approx(1.0));
    // a clip too short to describe keeps the learned factors
    CHECK(stargan::tempo_descriptor(timed_clip("new", "neutral", 0.3).motion).empty());
    CHECK(t.factors({}, learned) == learned);
    CHECK_THROWS_AS(t.factors({1.0, 2.0}, learned), shape_error);
    CHECK_THROWS_AS(t.factors(stargan::tempo_descriptor(timed_clip("new", "neutral", 2.2).motion), {1.0}), shape_error);
}

TEST_CASE("tempo neighbours: where every content changes its duration alike, the learned factors stay (a tie keeps them)")
{
    const std::vector<std::string> domains{"neutral", "sad"};
    std::vector<labelled_clip> d;
    for (int i = 0; i < 4; ++i) {
        const std::string c = "c" + std::to_string(i);
        d.push_back(timed_clip(c, "neutral", 1.0 + i)), d.push_back(timed_clip(c, "sad", 2.0 * (1.0 + i)));
    }
    const auto t = stargan::tempo_neighbours_fit(d, domains, "neutral");
    for (double e : t.errors) CHECK(e == doctest::Approx(0.0).epsilon(1e-12));
    CHECK(t.empty());
    CHECK(t.factors({}, {1.0, 2.0}) == std::vector<double>{1.0, 2.0});
}

TEST_CASE("tempo neighbours: no check with fewer than two contents, and a domain no neighbour has keeps its learned factor")
{
    const std::vector<std::string> domains{"neutral", "sad", "happy"};
    std::vector<labelled_clip> one{timed_clip("a", "neutral", 2.0), timed_clip("a", "sad", 4.0)};
    const auto none = stargan::tempo_neighbours_fit(one, domains, "neutral");
    CHECK(none.empty());
    for (double e : none.errors) CHECK(std::isnan(e));
    // happy only on the walks: a gesture's nearest neighbours have no happy pair, so happy keeps the learned factor
    auto d = two_kinds();
    d.push_back(timed_clip("walk0", "happy", 3.0)), d.push_back(timed_clip("walk1", "happy", 3.0));
    const auto t = stargan::tempo_neighbours_fit(d, domains, "neutral");
    REQUIRE(t.k == 1);
    CHECK(std::isnan(t.log_ratios[0][2]));
    const auto f = t.factors(stargan::tempo_descriptor(timed_clip("new", "neutral", 2.0).motion), {1.0, 1.5, 0.8});
    CHECK(f[1] == doctest::Approx(3.0));
    CHECK(f[2] == 0.8);
}

TEST_CASE("tempo neighbours: the checkpoint's field round-trips and a malformed one is refused naming the field")
{
    const std::vector<std::string> domains{"neutral", "sad"};
    const auto t = stargan::tempo_neighbours_fit(two_kinds(), domains, "neutral");
    REQUIRE(!t.empty());
    const auto fail = [](const std::string& what) { return format_error("checkpoint: m.safetensors: " + what); };
    const auto j = stargan::detail::tempo_neighbours_json(t);
    const auto back = stargan::detail::parse_tempo_neighbours(j, 2, fail);
    CHECK(back.k == t.k);
    CHECK(back.contents == t.contents);
    CHECK(back.descriptors == t.descriptors);
    CHECK(back.mean == t.mean);
    CHECK(back.scale == t.scale);
    CHECK(back.log_ratios[0][1] == t.log_ratios[0][1]);
    const auto refused = [&](nlohmann::json bad, const std::string& what) {
        CHECK_THROWS_WITH_AS(stargan::detail::parse_tempo_neighbours(bad, 2, fail), doctest::Contains(what.c_str()), format_error);
    };
    auto bad = j;
    bad["k"] = 0;
    refused(bad, "'tempo_neighbours' k is 0");
    bad = j, bad["k"] = 2.5;
    refused(bad, "'tempo_neighbours' k is 2.5");
    bad = j, bad["log_ratios"][1][1] = 9.0;
    refused(bad, "content 'gesture1' hold");
    bad = j, bad["log_ratios"][2] = {nullptr, nullptr};
    refused(bad, "content 'walk0' are all null");
    bad = j, bad["log_ratios"][0] = {0.0};
    refused(bad, "1 entries for 2 domains");
    bad = j, bad["scale"][0] = -1.0;
    refused(bad, "scale of feature 0");
    bad = j, bad["descriptors"].erase(1);
    refused(bad, "3 descriptors");
    bad = j, bad["mean"] = {0.0};
    refused(bad, "standardisation of 1 means");
    bad = j, bad["contents"] = {"a"};
    refused(bad, "4 descriptors and 4 rows of log ratios for 1 contents");
    bad = j, bad["k"] = 4;
    refused(bad, "expected an integer in 1..3");
    CHECK_THROWS_AS(stargan::detail::parse_tempo_neighbours(nlohmann::json::array(), 2, fail), format_error);
}

TEST_CASE("tempo neighbours in a model: the transfer, the statistics and the continuous control take the input's factors")
{
    using namespace handemo::stargan;
    const auto clips = toy_set();
    const auto d = fresh_dir("handemo_tempo_neighbours_model");
    auto o = handemo_options();
    o.iters = 3, o.threads = 1, o.progress_out = nullptr, o.gate_folds = 0;
    trainer<hand_tiny> tr(tiny_info(), prepare_data<hand_tiny>(clips, tiny_info(), o), o);
    tr.run(d);
    auto [f, info] = read_checkpoint(d / "checkpoint.safetensors");
    REQUIRE(info.tempo_table.empty());
    const clip& in = clips.front().motion;
    const auto desc = tempo_descriptor(in);
    REQUIRE(desc.size() == tempo_descriptor_size);
    // two contents: "near" is the input itself, "far" is far from it on every feature; one neighbour
    const std::size_t C = info.domains.size();
    tempo_neighbours t;
    t.k = 1;
    t.contents = {"far", "near"};
    t.descriptors = {desc, desc};
    for (auto& v : t.descriptors[0]) v += 100;
    t.mean.assign(tempo_descriptor_size, 0.0), t.scale.assign(tempo_descriptor_size, 1.0);
    t.log_ratios.assign(2, std::vector<double>(C, std::log(3.0)));
    for (std::size_t c = 0; c < C; ++c) t.log_ratios[1][c] = std::log(1.0 + 0.25 * static_cast<double>(c));
    const std::size_t neutral = static_cast<std::size_t>(std::find(info.domains.begin(), info.domains.end(), info.neutral) - info.domains.begin());
    REQUIRE(neutral < C);
    t.log_ratios[0][neutral] = t.log_ratios[1][neutral] = std::nan("");
    info.tempo_table = t;
    const auto model = load_model(f, info);
    const auto factors = model->input_tempo(in);
    for (std::size_t c = 0; c < C; ++c)
        if (c != neutral) CHECK(factors[c] == doctest::Approx(1.0 + 0.25 * static_cast<double>(c)));
    CHECK(factors[neutral] == info.tempo[neutral]);
    const std::size_t other = neutral == 0 ? 1 : 0;
    for (std::size_t c = 0; c < C; ++c) {
        if (c == neutral) continue;
        const auto& target = info.domains[c];
        const double want = factors[c] / factors[neutral];
        CHECK(model->tempo(in, target) == want);
        CHECK(model->transfer(in, target).tempo == want);
        CHECK(model->statistics(in, target).tempo == want);
        CHECK(model->transfer(in, target).motion.frames == emotion_model::output_frames(in.frames, want));
        // from another source: the ratio of the input's factors
        CHECK(model->tempo(in, target, info.domains[other]) == doctest::Approx(factors[c] / factors[other]));
    }
    // the continuous control at a label's own point: the discrete transfer's tempo
    const auto table = load_circumplex(std::string(HANDEMO_SOURCE_DIR) + "/data/rcm/circumplex.json");
    const continuous_control control(*model, table);
    const auto& target = info.domains[other];
    const auto& p = table.at(target);
    CHECK(control.transfer(in, p.valence, p.arousal).tempo == model->tempo(in, target));
    // a model without the table: the learned factors whatever the input
    info.tempo_table = {};
    const auto plain = load_model(f, info);
    CHECK(plain->tempo(in, target) == plain->tempo(target));
    CHECK(plain->input_tempo(in) == info.tempo);
    std::filesystem::remove_all(d);
}
