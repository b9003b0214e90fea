// The continuous control (stargan/continuous.hpp): at each label's point the discrete transfer bit for bit (the
// shipped model), and on a toy model with known continuous styles (G adds a known change per emotion; tempo,
// amplitude and posture prior known per emotion) the output at any point is the style the weights make, the
// classifier's posterior rises monotonically from neutral to each label, and keyframes move no faster than the
// weights' Lipschitz bound allows.
#include "helpers.hpp"
#include "../retarget/rigs.hpp"

#include <handemo/eval/continuous.hpp>
#include <handemo/metrics/classifier.hpp>
#include <handemo/metrics/full_rate_judge.hpp>
#include <handemo/stargan/continuous.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <tuple>
#include <vector>

using namespace handemo;

namespace {

circumplex_table continuous_table() { return load_circumplex(std::string(HANDEMO_SOURCE_DIR) + "/data/rcm/circumplex.json"); }

/// The shipped model, loaded once.
const stargan::emotion_model& continuous_shipped_model()
{
    static const auto m = stargan::load_model(std::string(HANDEMO_SOURCE_DIR) + "/data/models/hand-embedded");
    return *m;
}

/// A toy model with known styles: the shipped model's description (skeleton, range, domains), its G replaced by
/// one that adds a known change per target emotion (a bend of the first channel of every joint growing to the
/// middle keyframe, scale toy_bend(d)), and known tempo, amplitude, posture prior and gate per emotion.
class toy_model final : public stargan::emotion_model {
public:
    static double toy_bend(std::size_t d) { return 0.08 * static_cast<double>(d) - 0.12; }

    explicit toy_model(stargan::checkpoint_info info) : emotion_model(std::move(info)) {}

    /// with_lag: every joint of every emotion but neutral also lags by its own amount (train_options::lag)
    static std::unique_ptr<toy_model> make(bool with_lag = false)
    {
        auto info = continuous_shipped_model().info();
        const std::size_t D = info.domains.size(), C = info.range.joints * 3;
        info.options["residual"] = true;
        info.options["amplitude"] = true;
        info.tempo.assign(D, 1.0);
        info.amplitude.assign(D, 1.0);
        info.gate_posture.assign(D, 1.0);
        info.gate_motion.assign(D, 1.0);
        info.gate_prior.assign(D, 1.0);
        info.prior_posture.assign(D, std::vector<double>(C, 0.0));
        info.posture_centre.clear();  // the toy's change is its bend as it is (the shipped model's centre is its G's)
        for (std::size_t d = 0; d < D; ++d) {
            // the synthetic hand data's own styles: tempo and amplitude of the emotion, a posture of its own
            const auto st = style_of(emotion_from_string(info.domains[d]));
            info.tempo[d] = st.tempo;
            info.amplitude[d] = st.amplitude;
            for (std::size_t ch = 0; ch < C; ++ch) info.prior_posture[d][ch] = st.droop_deg * ((ch % 3) == 0 ? 1.0 : 0.25) + 2.0 * std::sin(0.7 * double(ch * (d + 1)));
            info.gate_posture[d] = 0.5 + 0.1 * static_cast<double>(d);
            info.gate_motion[d] = 1.0 - 0.1 * static_cast<double>(d);
            info.gate_prior[d] = 0.9;
        }
        if (with_lag) {
            info.lag.assign(D, std::vector<double>(info.range.joints, 0.0));
            for (std::size_t d = 0; d < D; ++d)
                for (std::size_t j = 0; j < info.range.joints && info.domains[d] != info.neutral; ++j)
                    info.lag[d][j] = 0.125 * static_cast<double>((j * (d + 3)) % 13) - 0.5;
        }
        auto m = std::make_unique<toy_model>(std::move(info));
        // the toy's bends take fingers past the hand's limits: its known algebra holds without them (the limits' own
        // cases are in limits_test.cpp)
        const double inf = std::numeric_limits<double>::infinity();
        m->set_limits(std::vector<double>(C, -inf), std::vector<double>(C, inf));
        return m;
    }

    mutable std::size_t generator_runs = 0;  ///< G runs so far (the grid's test counts them)

private:
    std::unique_ptr<workspace::scratch> new_scratch() const override { return std::make_unique<workspace::scratch>(); }
    void run_generator(const float* x, std::size_t target, float* out, workspace::scratch&) const override
    {
        ++generator_runs;
        const std::size_t K = keyframes(), J = joints(), plane = K * J;
        std::copy(x, x + 3 * plane, out);
        for (std::size_t k = 0; k < K; ++k)
            for (std::size_t j = 0; j < J; ++j)
                out[k * J + j] += static_cast<float>(toy_bend(target) * std::sin(3.14159265358979 * double(k) / double(K - 1)));
    }
};

/// The neutral take 0 of a synthetic motion.
clip continuous_neutral(hand_motion m) { return synthesize(m, emotion::neutral, 0, 3, 60.0); }

/// The point a fraction t of the way from neutral's point to label `name`'s.
std::pair<double, double> toward(const circumplex_table& t, const std::string& name, double f)
{
    const auto &n = t.at("neutral"), &l = t.at(name);
    return {n.valence + f * (l.valence - n.valence), n.arousal + f * (l.arousal - n.arousal)};
}

double max_abs_diff(const std::vector<double>& a, const std::vector<double>& b)
{
    double m = 0;
    for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, std::abs(a[i] - b[i]));
    return m;
}

}  // namespace

TEST_CASE("continuous transfer: at each label's point the output is the discrete transfer, bit for bit")
{
    const auto& model = continuous_shipped_model();
    const auto table = continuous_table();
    for (const auto rates : {stargan::rate_blend::linear, stargan::rate_blend::geometric}) {
    const std::string blend_name = stargan::rate_blend_name(rates);
    CAPTURE(blend_name);
    const stargan::continuous_control control(model, table, rates);
    for (hand_motion m : {hand_motion::pointing, hand_motion::crawling}) {
        const clip in = continuous_neutral(m);
        for (const auto& d : model.info().domains) {
            CAPTURE(d);
            const auto& p = table.at(d);
            const auto w = control.weights(p.valence, p.arousal);
            for (std::size_t i = 0; i < w.size(); ++i) CHECK(w[i] == (model.info().domains[i] == d ? 1.0 : 0.0));
            const auto c = control.transfer(in, p.valence, p.arousal);
            const auto r = model.transfer(in, d);
            REQUIRE(c.motion.frames == r.motion.frames);
            CHECK(c.motion.angles == r.motion.angles);  // bit for bit
            CHECK(c.motion.positions == r.motion.positions);
            CHECK(c.tempo == r.tempo);
            CHECK(c.amplitude == r.amplitude);
        }
    }
    // from another source emotion too (the tempo and amplitude ratios are to the source's)
    const clip sad = synthesize(hand_motion::patting, emotion::sad, 0, 3, 60.0);
    const auto& h = table.at("happy");
    const auto c = control.transfer(sad, h.valence, h.arousal, "sad");
    const auto r = model.transfer(sad, "happy", "sad");
    CHECK(c.motion.angles == r.motion.angles);
    // a capture on another skeleton, through retargeting and back
    const clip cap = test::random_motion(test::make_rig(test::openxr_names('r', false), {}), 90, 4, 15);
    const auto& a = table.at("angry");
    const auto cc = stargan::transfer_capture(control, cap, std::pair{a.valence, a.arousal});
    const auto rc = stargan::transfer_capture(model, cap, "angry");
    CHECK(cc.motion.angles == rc.motion.angles);
    CHECK(cc.retargeted);
    }
}

TEST_CASE("continuous transfer: a toy model with known styles gives, at any point, the style the weights make")
{
    const auto toy = toy_model::make();
    const auto& info = toy->info();
    const auto table = continuous_table();
    for (const auto rates : {stargan::rate_blend::linear, stargan::rate_blend::geometric}) {
    const std::string blend_name = stargan::rate_blend_name(rates);
    CAPTURE(blend_name);
    const bool geometric = rates == stargan::rate_blend::geometric;
    const stargan::continuous_control control(*toy, table, rates);
    const clip in = continuous_neutral(hand_motion::gripping);
    const std::size_t K = toy->keyframes(), C = toy->joints() * 3, D = info.domains.size();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int n = 0; n < 12; ++n) {
        double v = u(rng), a = u(rng);
        if (v * v + a * a > 1) continue;
        CAPTURE(v);
        CAPTURE(a);
        const auto w = control.weights(v, a);
        const auto r = control.transfer(in, v, a);
        // the known style: the input's keyframes in the neutral's amplitude space, each label's gated change and
        // prior weighted, then the weighted amplitude
        auto kf = extract_keyframes<dynamic_keyframes>(in, K);
        stargan::scale_keyframe_excursions(kf, 1.0 / info.amplitude[toy->domain("neutral")], info.amplitude_anchor);
        auto expect = kf;
        double amp = 0, tempo = 0;
        for (std::size_t d = 0; d < D; ++d) {
            // linear: the weighted factors; geometric: the weighted logs of the factors
            amp += w[d] * (geometric ? std::log(info.amplitude[d]) : info.amplitude[d]);
            tempo += w[d] * (geometric ? std::log(info.tempo[d]) : info.tempo[d]);
            double mean_change = 0;
            for (std::size_t k = 0; k < K; ++k) mean_change += toy_model::toy_bend(d) * std::sin(3.14159265358979 * double(k) / double(K - 1)) / double(K);
            for (std::size_t k = 0; k < K; ++k)
                for (std::size_t ch = 0; ch < C; ++ch) {
                    const double half = info.range.half_span(ch);
                    const double change = (ch % 3 == 0 ? toy_model::toy_bend(d) * std::sin(3.14159265358979 * double(k) / double(K - 1)) : 0.0) * half;
                    const double mean = (ch % 3 == 0 ? mean_change : 0.0) * half;
                    expect.angles[k * C + ch] +=
                        w[d] * (info.gate_posture[d] * mean + info.gate_motion[d] * (change - mean) + info.gate_prior[d] * info.prior_posture[d][ch]);
                }
        }
        if (geometric) amp = std::exp(amp), tempo = std::exp(tempo);
        stargan::scale_keyframe_excursions(expect, amp, info.amplitude_anchor);
        CHECK(max_abs_diff(r.keys.angles, expect.angles) < 1e-3);  // G runs in float
        CHECK(r.tempo == doctest::Approx(tempo / info.tempo[toy->domain("neutral")]).epsilon(1e-12));
        CHECK(r.motion.frames == stargan::emotion_model::output_frames(in.frames, r.tempo));
    }
    // halfway from neutral to sad: the geometric blend's duration factor is the geometric mean of the two labels'
    // (relative to the neutral input), the linear blend's the arithmetic mean
    const auto [hv, ha] = toward(table, "sad", 0.5);
    const double fs = info.tempo[toy->domain("sad")], fn = info.tempo[toy->domain("neutral")];
    REQUIRE(std::abs(std::log(fs / fn)) > std::log(1.5));  // far enough apart that the two means differ
    CHECK(control.transfer(in, hv, ha).tempo == doctest::Approx(geometric ? std::sqrt(fs / fn) : 0.5 * (fs + fn) / fn).epsilon(1e-12));
    }
}

TEST_CASE("rate blends: linear and geometric, exact at one-hot weights, non-positive factors refused by the geometric blend")
{
    using stargan::rate_blend;
    const std::vector<double> f{1.0, 4.0, 0.5};
    CHECK(stargan::blend_rates(f, {0.5, 0.5, 0.0}, rate_blend::linear, "tempo") == doctest::Approx(2.5).epsilon(1e-15));
    CHECK(stargan::blend_rates(f, {0.5, 0.5, 0.0}, rate_blend::geometric, "tempo") == doctest::Approx(2.0).epsilon(1e-15));
    CHECK(stargan::blend_rates(f, {0.0, 0.5, 0.5}, rate_blend::geometric, "tempo") == doctest::Approx(std::sqrt(2.0)).epsilon(1e-15));
    CHECK(stargan::blend_rates(f, {0.25, 0.25, 0.5}, rate_blend::geometric, "tempo") == doctest::Approx(1.0).epsilon(1e-15));
    // a weight of exactly 1 gives the factor itself, also where exp(log(f)) is not f (so the labels' points stay exact)
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.2, 5.0);
    std::size_t inexact = 0;
    for (int n = 0; n < 2000; ++n) {
        const double x = u(rng);
        inexact += std::exp(std::log(x)) != x;
        for (const auto b : {rate_blend::linear, rate_blend::geometric}) {
            CHECK(stargan::blend_rates({1.0, x, 2.0}, {0.0, 1.0, 0.0}, b, "tempo") == x);
        }
    }
    REQUIRE(inexact > 0);  // the round trip through log and exp does lose bits on some of these factors
    // the geometric blend needs positive, finite factors; the linear one takes any
    CHECK_THROWS_WITH_AS(stargan::blend_rates({1.0, 0.0}, {0.5, 0.5}, rate_blend::geometric, "amplitude"),
                         doctest::Contains("the amplitude factor of label 1 is 0.000000, which a geometric blend cannot take"), value_error);
    CHECK_THROWS_AS(stargan::blend_rates({1.0, std::nan("")}, {0.5, 0.5}, rate_blend::geometric, "tempo"), value_error);
    CHECK(stargan::blend_rates({1.0, 0.0}, {0.5, 0.5}, rate_blend::linear, "amplitude") == 0.5);
    // names
    CHECK(stargan::parse_rate_blend("geometric") == rate_blend::geometric);
    CHECK(stargan::parse_rate_blend("linear") == rate_blend::linear);
    CHECK(std::string(stargan::rate_blend_name(rate_blend::geometric)) == "geometric");
    CHECK_THROWS_WITH_AS(stargan::parse_rate_blend("log", "transfer: --rate-blend"),
                         doctest::Contains("transfer: --rate-blend: unknown rate blend 'log', expected linear or geometric"), value_error);
}

TEST_CASE("the joint lag: after G's change and the prior, before the amplitude stage; exact at the labels' points")
{
    const auto plain = toy_model::make(false), lagged = toy_model::make(true);
    const auto& info = lagged->info();
    const clip in = continuous_neutral(hand_motion::crawling);
    const clip sad = synthesize(hand_motion::crawling, emotion::sad, 0, 3, 60.0);
    for (const auto& [input, source] : {std::pair<const clip*, std::string>{&in, "neutral"}, {&sad, "sad"}})
        for (const auto& t : info.domains) {
            CAPTURE(t);
            CAPTURE(source);
            const std::size_t d = lagged->domain(t), s = lagged->domain(source);
            const auto pl = plain->parts(*input, t, source), pg = lagged->parts(*input, t, source);
            REQUIRE(pl.lag.empty());
            // the lag is the target's minus the source's, per joint
            std::vector<double> want(info.range.joints);
            for (std::size_t j = 0; j < want.size(); ++j) want[j] = info.lag[d][j] - info.lag[s][j];
            if (d == s)
                CHECK(pg.lag.empty());
            else
                CHECK(pg.lag == want);
            for (const auto& [posture, motion, prior] : {std::tuple{1.0, 1.0, 0.0}, {0.0, 0.0, 1.0}, {0.5, 0.25, 0.75}}) {
                auto p1 = pl;
                p1.amplitude = 1.0;
                auto expect = plain->combine(p1, posture, motion, prior);
                if (d != s) stargan::shift_joints(expect, want);
                stargan::scale_keyframe_excursions(expect, pl.amplitude, info.amplitude_anchor);
                const auto got = lagged->combine(pg, posture, motion, prior);
                CHECK(max_abs_diff(got.angles, expect.angles) < 1e-12);
            }
            // statistics() is the (0, 0, 1) setting, lag included
            if (source == "neutral") {
                const auto st = lagged->statistics(*input, t);
                const auto fin = lagged->finish(*input, pg, 0, 0, 1);
                CHECK(max_abs_diff(st.motion.angles, fin.angles) < 1e-9);
            }
        }
    // a lag that moves something: fearful's output differs from the model without lags
    const auto a = lagged->transfer(in, "fearful"), b = plain->transfer(in, "fearful");
    CHECK(max_abs_diff(a.motion.angles, b.motion.angles) > 1.0);
    // the continuous control blends the lagged labels and is still the discrete transfer at each label's point
    const auto table = continuous_table();
    const stargan::continuous_control control(*lagged, table);
    for (const auto& d : info.domains) {
        CAPTURE(d);
        const auto& p = table.at(d);
        CHECK(control.transfer(in, p.valence, p.arousal).motion.angles == lagged->transfer(in, d).motion.angles);
    }
}

TEST_CASE("continuous transfer about the ends (--amplitude-anchor ends): exact at the labels' points, a still target too")
{
    auto info = toy_model::make()->info();
    info.amplitude_anchor = stargan::amplitude_anchor::ends;
    const toy_model model(info);
    const auto table = continuous_table();
    const stargan::continuous_control control(model, table);
    const clip in = continuous_neutral(hand_motion::pushing);
    for (const auto& d : info.domains) {
        CAPTURE(d);
        const auto& p = table.at(d);
        const auto c = control.transfer(in, p.valence, p.arousal);
        const auto r = model.transfer(in, d);
        CHECK(r.amplitude_anchor == stargan::amplitude_anchor::ends);
        CHECK(c.motion.angles == r.motion.angles);  // bit for bit
        // a target that stays at the label's point over the clip: the same keyframes
        va_curve still;
        still.time = {0.0};
        still.valence = {p.valence};
        still.arousal = {p.arousal};
        const auto m = control.transfer(in, still);
        CHECK(max_abs_diff(m.keys.angles, c.keys.angles) < 1e-9);
    }
    // between labels the blend is scaled about the blend's ends, which are the blended ends
    const auto w = control.weights(0.2, 0.3);
    const auto c = control.transfer(in, 0.2, 0.3);
    const std::size_t C = model.joints() * 3, K = model.keyframes();
    double moved = 0;
    for (std::size_t ch = 0; ch < C; ++ch) {
        const double first = c.keys.angles[ch], last = c.keys.angles[(K - 1) * C + ch];
        const auto ends = [&](const auto& k) { return 0.5 * (k.angles[ch] + k.angles[(K - 1) * C + ch]); };
        double blended = 0;
        for (std::size_t d = 0; d < w.size(); ++d)
            if (w[d] > 0) blended += w[d] * ends(model.combine(model.parts(in, info.domains[d]), info.gate_posture[d], info.gate_motion[d], info.gate_prior[d]));
        moved = std::max(moved, std::abs(0.5 * (first + last) - blended));
    }
    CHECK(moved < 1e-9);
}

TEST_CASE("continuous transfer: along straight paths from neutral the classifier's posterior rises monotonically (toy)")
{
    const auto toy = toy_model::make();
    const auto table = continuous_table();
    const stargan::continuous_control control(*toy, table);
    const auto& domains = toy->info().domains;
    // the independent classifier, fitted on the toy's outputs at the labels' points for every motion type
    std::vector<std::vector<double>> x;
    std::vector<std::string> y;
    const auto features = [](const clip& c) { return metrics::motion_features(extract_keyframes<dynamic_keyframes>(c, 9), c.duration()); };
    for (hand_motion m : all_hand_motions)
        for (int take = 0; take < 2; ++take) {
            const clip in = synthesize(m, emotion::neutral, take, 3, 60.0);
            const auto lk = control.prepare(in);
            for (const auto& d : domains) {
                const auto& p = table.at(d);
                x.push_back(features(control.transfer(in, lk, p.valence, p.arousal).motion));
                y.push_back(d);
            }
        }
    metrics::nearest_centroid_classifier clf;
    clf.fit(x, y, 0.5);
    std::size_t monotone = 0, paths = 0;
    for (hand_motion m : all_hand_motions) {
        const clip in = continuous_neutral(m);
        const auto lk = control.prepare(in);
        for (const auto& d : domains) {
            if (d == "neutral") continue;
            CAPTURE(d);
            // the log of the posterior (it rises exactly when the posterior does), from the distances: the
            // posterior itself underflows to 0 far from the label, where a fall would go unseen
            double prev = -1e300;
            bool rising = true;
            for (int s = 0; s <= 10; ++s) {
                const auto [v, a] = toward(table, d, s / 10.0);
                const auto dist = clf.distances(features(control.transfer(in, lk, v, a).motion));
                const double dmin = *std::min_element(dist.begin(), dist.end());
                double z = 0;
                for (double x : dist) z += std::exp(-0.5 * (x - dmin));
                const double log_post = -0.5 * (dist[clf.index_of(d)] - dmin) - std::log(z);
                rising = rising && log_post >= prev - 1e-9 * std::abs(prev);
                prev = log_post;
            }
            monotone += rising;
            ++paths;
        }
    }
    CHECK(paths == 28);
    CHECK(monotone == paths);
}

TEST_CASE("measure_continuous: the full-rate judge reads every path, halfway point and real clip against its neutral reference")
{
    const auto toy = toy_model::make();
    const auto table = continuous_table();
    const stargan::continuous_control control(*toy, table);
    const auto& domains = toy->info().domains;
    // the judge, fitted on the toy's outputs at the labels' points read against their inputs
    // (and the centroid classifier measure_continuous also takes, on the same outputs' keyframe features)
    std::vector<std::vector<double>> x, r, kx;
    std::vector<std::string> y, g;
    const auto kf = [](const clip& c) { return metrics::motion_features(extract_keyframes<9>(c), metrics::measure<9>(c).duration); };
    for (hand_motion m : all_hand_motions) {
        if (m == hand_motion::patting) continue;  // held out below
        for (int take = 0; take < 2; ++take) {
            const clip in = synthesize(m, emotion::neutral, take, 3, 60.0);
            const auto in_f = metrics::full_rate_features(in);
            const auto lk = control.prepare(in);
            for (const auto& d : domains) {
                const auto& p = table.at(d);
                const clip out = control.transfer(in, lk, p.valence, p.arousal).motion;
                x.push_back(metrics::full_rate_features(out)), kx.push_back(kf(out));
                r.push_back(in_f), y.push_back(d), g.push_back(std::string(to_string(m)));
            }
        }
    }
    metrics::full_rate_judge judge;
    judge.fit(x, r, y, g, {metrics::full_rate_inputs::pooled});
    metrics::nearest_centroid_classifier clf;
    clf.fit(kx, y, 0.5);
    // a held-out motion: its neutral takes the inputs, its real clips each read against its own take's neutral clip
    const clip in0 = synthesize(hand_motion::patting, emotion::neutral, 0, 3, 60.0), in1 = synthesize(hand_motion::patting, emotion::neutral, 1, 3, 60.0);
    std::vector<clip> real_clips;
    std::vector<std::string> real_emotions;
    for (int take = 0; take < 2; ++take)
        for (const auto& d : domains) real_clips.push_back(synthesize(hand_motion::patting, emotion_from_string(d), take, 3, 60.0)), real_emotions.push_back(d);
    std::vector<std::pair<const clip*, std::string>> reals;
    std::vector<const clip*> refs;
    for (std::size_t i = 0; i < real_clips.size(); ++i) reals.emplace_back(&real_clips[i], real_emotions[i]), refs.push_back(i < domains.size() ? &in0 : &in1);
    const std::vector<const clip*> inputs{&in0, &in1};
    const auto f = eval::measure_continuous<9>(*toy, control, clf, inputs, reals, "patting", 10, {}, &judge, refs);
    // the same counts computed here from the judge's probabilities
    const auto third = [](const std::string& p, const std::string& label) { return p != label && p != "neutral"; };
    const auto argmax = [&](const std::vector<double>& p) { return judge.classifier().classes()[static_cast<std::size_t>(std::max_element(p.begin(), p.end()) - p.begin())]; };
    std::size_t monotone = 0, peak = 0, halfway_third = 0, real_third = 0, real = 0;
    for (const clip* in : inputs) {
        const auto in_f = metrics::full_rate_features(*in);
        const auto lk = control.prepare(*in);
        for (const auto& d : domains) {
            if (d == "neutral") continue;
            std::vector<double> lp;
            for (int s = 0; s <= 10; ++s) {
                const auto [v, a] = toward(table, d, s / 10.0);
                const auto p = judge.probabilities(metrics::full_rate_features(control.transfer(*in, lk, v, a).motion), in_f);
                lp.push_back(std::log(p.at(judge.classifier().index_of(d))));
                if (s == 5) halfway_third += third(argmax(p), d);
            }
            const auto shape = eval::shape_of_path(lp);
            monotone += shape.monotone, peak += !shape.monotone && shape.peak_before_label;
        }
    }
    for (std::size_t i = 0; i < reals.size(); ++i) {
        if (real_emotions[i] == "neutral") continue;
        ++real;
        real_third += third(judge.predict(metrics::full_rate_features(real_clips[i]), metrics::full_rate_features(*refs[i])), real_emotions[i]);
    }
    CHECK(f.full_judge);
    CHECK(f.paths == 8);
    CHECK(f.monotone_full == monotone);
    CHECK(f.peak_before_label_full == peak);
    CHECK(f.halfway_third_full == halfway_third);
    CHECK(f.real_full == real);
    CHECK(f.real_third_full == real_third);
    CHECK(real == 8);
    // the judge's table in the report, its total row
    const auto sec = eval::continuous_section({f});
    CHECK(sec.markdown.find("read by the full-rate judge") != std::string::npos);
    char total[96];
    std::snprintf(total, sizeof total, "| all | %zu / 8 (", monotone);
    CHECK(sec.markdown.find(total) != std::string::npos);
    // without a judge: nothing of it measured or reported; references that do not match the real clips are refused
    const auto plain = eval::measure_continuous<9>(*toy, control, clf, inputs, reals, "patting", 10);
    CHECK_FALSE(plain.full_judge);
    CHECK(plain.monotone == f.monotone);
    CHECK(eval::continuous_section({plain}).markdown.find("read by the full-rate judge") == std::string::npos);
    CHECK_THROWS_WITH_AS(eval::measure_continuous<9>(*toy, control, clf, inputs, reals, "patting", 10, {}, &judge, {}),
                         doctest::Contains("0 neutral references for 10 real clips"), value_error);
    CHECK(eval::log_probability({0.25, 0.0}, 0) == std::log(0.25));
    CHECK(eval::log_probability({0.25, 0.0}, 1) == -1e300);
    CHECK(eval::log_probability({0.25, 0.0}, 2) == -1e300);
}

TEST_CASE("continuous transfer: keyframes move at most the weights' Lipschitz bound per unit of circumplex distance")
{
    // |K(p) - K(q)| <= 1/2 sum_l |w_l(p) - w_l(q)| max_{l,m} |K_l - K_m| before the amplitude stage: checked
    // on the shipped model (no amplitude factor in between: a model without the stage would be the same)
    const auto& model = continuous_shipped_model();
    const auto table = continuous_table();
    const stargan::continuous_control control(model, table);
    const clip in = continuous_neutral(hand_motion::patting);
    const auto lk = control.prepare(in);
    const std::size_t D = model.info().domains.size();
    double spread = 0;  // max_{l,m} |K_l - K_m|
    for (std::size_t i = 0; i < D; ++i)
        for (std::size_t j = 0; j < D; ++j) spread = std::max(spread, max_abs_diff(lk.keys[i].angles, lk.keys[j].angles));
    // the keyframes before the amplitude stage: the blend with every amplitude taken as 1 is a convex sum
    const auto pre = [&](const std::vector<double>& w) {
        std::vector<double> out(lk.keys[0].angles.size(), 0.0);
        for (std::size_t d = 0; d < D; ++d)
            for (std::size_t i = 0; i < out.size(); ++i) out[i] += w[d] * lk.keys[d].angles[i];
        return out;
    };
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> u(-1, 1), step(-0.02, 0.02);
    double worst_weights = 0, worst_keys = 0;
    for (int n = 0; n < 400; ++n) {
        const double v = u(rng), a = u(rng), v2 = v + step(rng), a2 = a + step(rng);
        if (v * v + a * a > 1 || v2 * v2 + a2 * a2 > 1) continue;
        const auto w = control.weights(v, a), w2 = control.weights(v2, a2);
        double l1 = 0;
        for (std::size_t d = 0; d < D; ++d) l1 += std::abs(w[d] - w2[d]);
        const double dist = std::hypot(v - v2, a - a2);
        const double change = max_abs_diff(pre(w), pre(w2));
        CHECK(change <= 0.5 * l1 * spread + 1e-9);
        worst_weights = std::max(worst_weights, l1 / dist);
        worst_keys = std::max(worst_keys, change / dist);
    }
    // the weights are Lipschitz: their L1 change per unit distance stays bounded (the closest labels' angle sets
    // it), and so the keyframes' change per unit distance is at most half that times the labels' spread
    CHECK(worst_weights < 40);
    CHECK(worst_keys <= 0.5 * 40 * spread);
    MESSAGE("weights' L1 change per unit distance up to " << worst_weights << ", keyframes' up to " << worst_keys << " deg");
}

TEST_CASE("continuous transfer: a target that moves over the clip")
{
    const auto& model = continuous_shipped_model();
    const auto table = continuous_table();
    const stargan::continuous_control control(model, table);
    const clip in = continuous_neutral(hand_motion::pushing);
    // a curve that stays at one label's point is the discrete transfer's keyframes (the time warp resamples)
    const auto& s = table.at("sad");
    va_curve still;
    still.time = {0.0};
    still.valence = {s.valence};
    still.arousal = {s.arousal};
    const auto r = control.transfer(in, still);
    const auto d = control.transfer(in, s.valence, s.arousal);
    CHECK(r.keys.angles == d.keys.angles);
    CHECK(r.tempo == doctest::Approx(d.tempo).epsilon(1e-12));
    CHECK(r.motion.frames == d.motion.frames);
    CHECK(max_abs_diff(r.motion.angles, d.motion.angles) < 0.5);
    // neutral -> sad -> angry: the first keyframe is neutral's, the last angry's; the duration between
    const auto c = path_curve(parse_path("neutral,sad,angry", table.labels), static_cast<double>(in.frames - 1) / in.fps);
    const auto p = control.transfer(in, c);
    const std::size_t K = model.keyframes();
    CHECK(p.weights.size() == K);
    CHECK(p.weights.front()[model.domain("neutral")] == 1.0);
    CHECK(p.weights.back()[model.domain("angry")] == 1.0);
    CHECK(p.weights[K / 2][model.domain("sad")] == 1.0);
    const double lo = std::min({model.tempo("neutral"), model.tempo("sad"), model.tempo("angry")});
    const double hi = std::max({model.tempo("neutral"), model.tempo("sad"), model.tempo("angry")});
    CHECK(p.tempo >= lo);
    CHECK(p.tempo <= hi);
    CHECK(p.motion.frames == stargan::emotion_model::output_frames(in.frames, p.tempo));
}

TEST_CASE("continuous control: errors name the point, the label and the table")
{
    const auto& model = continuous_shipped_model();
    auto table = continuous_table();
    const stargan::continuous_control control(model, table);
    const clip in = continuous_neutral(hand_motion::pointing);
    CHECK_THROWS_WITH_AS(control.transfer(in, 0.9, 0.9), doctest::Contains("lies outside the circumplex"), value_error);
    table.labels.erase(std::remove_if(table.labels.begin(), table.labels.end(), [](const label_point& l) { return l.name == "fearful"; }),
                       table.labels.end());
    CHECK_THROWS_WITH_AS(stargan::continuous_control(model, table, "my.json"), doctest::Contains("label 'fearful' has no circumplex coordinates in my.json"),
                         value_error);
    stargan::capture_options o;
    o.detail = true;
    CHECK_THROWS_WITH_AS(stargan::transfer_capture(control, in, std::pair{0.1, 0.1}, {}, o), doctest::Contains("detail layer is per emotion"), value_error);
}

TEST_CASE("continuous transfer: a grid of points runs G once per label and gives each point's transfer, bit for bit (toy)")
{
    const auto toy = toy_model::make();
    const auto table = continuous_table();
    const stargan::continuous_control control(*toy, table);
    auto points = va_grid(3);
    const auto& sad = table.at("sad");
    points.emplace_back(sad.valence, sad.arousal);
    const std::size_t D = toy->info().domains.size();
    const clip in = continuous_neutral(hand_motion::pointing);
    const clip cap = test::random_motion(test::make_rig(test::openxr_names('r', false), {}), 60, 4, 15);
    for (const clip* c : {&in, &cap}) {
        toy->generator_runs = 0;
        const auto out = stargan::transfer_capture_points(control, *c, points);
        CHECK(toy->generator_runs == D);  // one prepare(): G once per label, not once per point
        REQUIRE(out.size() == points.size());
        for (std::size_t k = 0; k < points.size(); ++k) {
            CAPTURE(k);
            const auto one = stargan::transfer_capture(control, *c, points[k]).motion;
            REQUIRE(out[k].frames == one.frames);
            CHECK(out[k].angles == one.angles);
            CHECK(out[k].positions == one.positions);
            CHECK(out[k].skel.size() == c->skel.size());  // written back onto the capture's own skeleton
        }
    }
    CHECK_THROWS_WITH_AS(stargan::transfer_capture_points(control, in, {{0.9, 0.9}}), doctest::Contains("outside the circumplex"), value_error);
}
