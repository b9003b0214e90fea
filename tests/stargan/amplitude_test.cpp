// The amplitude stage's anchor (train_options::amplitude_anchor): scaling about the mean or about the ends, the
// check that chooses between them, the posture prior's correction and the checkpoint field.
#include <doctest/doctest.h>
#include <handemo/stargan.hpp>

#include "helpers.hpp"

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace handemo;
using namespace handemo::stargan;
using namespace handemo::test;

namespace {

constexpr std::size_t K = 9;

/// A labelled clip of exactly K frames (so its keyframes are its frames) on the hand skeleton, channel values from `f`.
template <class F>
labelled_clip frames_clip(const std::string& content, const std::string& emotion, const std::string& take, F f)
{
    labelled_clip c;
    c.path = content + "_" + emotion + "_" + take + ".bvh";
    c.content = content, c.emotion = emotion, c.take = take;
    c.motion = clip::make(hand_skeleton(), K, 30);
    const std::size_t C = c.motion.skel.size() * 3;
    for (std::size_t k = 0; k < K; ++k)
        for (std::size_t ch = 0; ch < C; ++ch) c.motion.angles[k * C + ch] = f(k, ch);
    return c;
}

/// Scale of each emotion's excursions in the toy sets below.
double scale_of(const std::string& e) { return e == "angry" ? 1.5 : e == "happy" ? 1.25 : e == "sad" ? 0.6 : e == "fearful" ? 0.8 : 1.0; }

/// 5 contents x 5 emotions x 2 takes. `rest`: each channel leaves a rest pose and comes back to it (a raised cosine,
/// zero at the first and last keyframe), the emotion scaling the movement away from rest; otherwise a sine whose
/// phase at the first keyframe differs per content and channel, scaled about its mean. A small per-take wobble.
std::vector<labelled_clip> toy(bool rest)
{
    std::vector<labelled_clip> out;
    for (int c = 0; c < 5; ++c)
        for (const char* e : {"neutral", "angry", "happy", "sad", "fearful"})
            for (int t = 0; t < 2; ++t) {
                const double s = scale_of(e);
                out.push_back(frames_clip("c" + std::to_string(c), e, std::to_string(t), [&](std::size_t k, std::size_t ch) {
                    const double base = 10.0 * std::sin(0.7 * double(ch) + double(c)), amp = 8.0 + 6.0 * std::cos(1.3 * double(ch) + 2.0 * c);
                    const double x = 2.0 * std::numbers::pi * 2.0 * double(k) / double(K - 1);
                    const double wobble = 0.3 * std::sin(1.7 * double(k) + double(ch) + 3.0 * t + 5.0 * c);
                    if (rest) return base + s * amp * 0.5 * (1.0 - std::cos(x)) + wobble;
                    return base + s * amp * std::sin(x + 0.9 * double(ch) + 1.1 * c) + wobble;
                }));
            }
    return out;
}

std::vector<keyframes<K>> keys_of(const std::vector<labelled_clip>& clips)
{
    std::vector<keyframes<K>> kfs;
    for (const auto& c : clips) kfs.push_back(extract_keyframes<K>(c.motion));
    return kfs;
}

}  // namespace

TEST_CASE("amplitude anchor: scaling about the ends keeps the ends' mean and 1/f undoes f; about the mean as before")
{
    const auto clips = toy(true);
    const auto kf = extract_keyframes<K>(clips[3].motion);
    const std::size_t C = kf.joints * 3;
    auto ends = kf;
    scale_keyframe_excursions(ends, 1.7, amplitude_anchor::ends);
    auto mean = kf;
    scale_keyframe_excursions(mean, 1.7);  // the default: about the mean
    double moved = 0;
    for (std::size_t ch = 0; ch < C; ++ch) {
        const double a = 0.5 * (kf.angles[ch] + kf.angles[(K - 1) * C + ch]);
        CHECK(excursion_anchor(ends, ch, amplitude_anchor::ends) == doctest::Approx(a).epsilon(1e-12));
        double m = 0;
        for (std::size_t k = 0; k < K; ++k) m += kf.angles[k * C + ch];
        m /= double(K);
        for (std::size_t k = 0; k < K; ++k) {
            // the mean path is the formula it always was
            CHECK(mean.angles[k * C + ch] == m + 1.7 * (kf.angles[k * C + ch] - m));
            CHECK(ends.angles[k * C + ch] == doctest::Approx(a + 1.7 * (kf.angles[k * C + ch] - a)).epsilon(1e-12));
            moved = std::max(moved, std::abs(ends.angles[k * C + ch] - mean.angles[k * C + ch]));
        }
    }
    CHECK(moved > 1.0);  // the two anchors differ on a movement away from rest
    scale_keyframe_excursions(ends, 1.0 / 1.7, amplitude_anchor::ends);
    for (std::size_t i = 0; i < kf.angles.size(); ++i) CHECK(ends.angles[i] == doctest::Approx(kf.angles[i]).epsilon(1e-12));
    // the excursion about the ends: root mean square distance from the ends' mean, summed over the channels
    double e = 0;
    for (std::size_t ch = 0; ch < C; ++ch) {
        const double a = excursion_anchor(kf, ch, amplitude_anchor::ends);
        double q = 0;
        for (std::size_t k = 0; k < K; ++k) q += (kf.angles[k * C + ch] - a) * (kf.angles[k * C + ch] - a);
        e += std::sqrt(q / double(K));
    }
    CHECK(keyframe_excursion(kf, amplitude_anchor::ends) == doctest::Approx(e).epsilon(1e-12));
    CHECK(parse_amplitude_anchor("ends", "test") == amplitude_anchor::ends);
    CHECK(std::string(anchor_name(amplitude_anchor::mean)) == "mean");
    CHECK_THROWS_WITH_AS(parse_amplitude_anchor("median", "train: amplitude_anchor"),
                         "train: amplitude_anchor: amplitude anchor 'median' is not 'mean' or 'ends'", value_error);
}

TEST_CASE("fit_amplitude: auto takes the ends for movements away from a rest pose, the mean for cycles cut anywhere")
{
    const auto domains = hand_domains();
    {
        const auto clips = toy(true);
        const auto kfs = keys_of(clips);
        const auto r = fit_amplitude<K>(clips, kfs, domains, "neutral", "auto");
        CHECK(r.anchor == amplitude_anchor::ends);
        CHECK(r.anchor_check.second < 0.5 * r.anchor_check.first);
        CHECK(r.check.second < r.check.first);  // the prior with scaling beats the prior alone
        for (std::size_t d = 0; d < domains.size(); ++d) CHECK(r.factors[d] == doctest::Approx(scale_of(domains[d])).epsilon(0.03));
        // "mean" is checked_amplitude_factors(), as before the anchor existed
        const auto m = fit_amplitude<K>(clips, kfs, domains, "neutral", "mean");
        const auto [check, factors] = checked_amplitude_factors<K>(clips, kfs, domains, "neutral");
        CHECK(m.anchor == amplitude_anchor::mean);
        CHECK(m.factors == factors);
        CHECK(m.check == check);
        CHECK(std::isnan(m.anchor_check.first));
    }
    {
        const auto clips = toy(false);
        const auto kfs = keys_of(clips);
        const auto r = fit_amplitude<K>(clips, kfs, domains, "neutral", "auto");
        CHECK(r.anchor == amplitude_anchor::mean);
        CHECK(r.anchor_check.first < r.anchor_check.second);
        for (std::size_t d = 0; d < domains.size(); ++d) CHECK(r.factors[d] == doctest::Approx(scale_of(domains[d])).epsilon(0.03));
        // forced to the ends: no choice made (NaN), the factors checked about the ends
        const auto e = fit_amplitude<K>(clips, kfs, domains, "neutral", "ends");
        CHECK(e.anchor == amplitude_anchor::ends);
        CHECK(std::isnan(e.anchor_check.first));
        CHECK(e.check == amplitude_prior_cv<K>(clips, kfs, domains, "neutral", amplitude_anchor::ends));
        CHECK(e.check.first < e.check.second);  // scaling about a wrong anchor loses to the prior alone, so no factors
        for (double v : e.factors) CHECK(v == 1.0);
    }
    CHECK_THROWS_AS(fit_amplitude<K>(toy(true), keys_of(toy(true)), domains, "neutral", "middle"), value_error);
}

TEST_CASE("posture prior about the ends: the prior and the scaling move the mean by the training pairs' mean change")
{
    const auto clips = toy(true);
    const auto kfs = keys_of(clips);
    const auto info = tiny_info();
    const auto amp = fit_amplitude<K>(clips, kfs, info.domain_names, "neutral", "ends");
    REQUIRE(amp.anchor == amplitude_anchor::ends);
    const auto plain = posture_prior<K>(clips, info);
    const auto prior = posture_prior<K>(clips, info, amp.factors, amplitude_anchor::ends);
    CHECK(posture_prior<K>(clips, info, amp.factors, amplitude_anchor::mean) == plain);  // about the mean: no correction
    const std::size_t C = kfs.front().joints * 3;
    for (std::size_t d = 0; d < info.domains; ++d) {
        const std::string& e = info.domain_names[d];
        if (e == "neutral") {
            CHECK(prior[d] == plain[d]);
            continue;
        }
        // statistics' pipeline on every training pair: the neutral take, the prior, the scaling about the ends
        std::vector<double> out_mean(C, 0.0), real_mean(C, 0.0), plain_mean(C, 0.0);
        std::size_t n = 0;
        for (std::size_t m = 0; m < clips.size(); ++m) {
            if (clips[m].emotion != e) continue;
            std::size_t q = 0;
            while (!(clips[q].emotion == "neutral" && clips[q].content == clips[m].content && clips[q].take == clips[m].take)) ++q;
            auto y = kfs[q], z = kfs[q];
            for (std::size_t i = 0; i < y.angles.size(); ++i) y.angles[i] += prior[d][i % C], z.angles[i] += plain[d][i % C];
            scale_keyframe_excursions(y, amp.factors[d], amplitude_anchor::ends);
            scale_keyframe_excursions(z, amp.factors[d], amplitude_anchor::ends);
            for (std::size_t ch = 0; ch < C; ++ch) {
                out_mean[ch] += excursion_anchor(y, ch, amplitude_anchor::mean);
                plain_mean[ch] += excursion_anchor(z, ch, amplitude_anchor::mean);
                real_mean[ch] += excursion_anchor(kfs[m], ch, amplitude_anchor::mean);
            }
            ++n;
        }
        REQUIRE(n == 10);
        double worst = 0, plain_worst = 0;
        for (std::size_t ch = 0; ch < C; ++ch) {
            worst = std::max(worst, std::abs(out_mean[ch] - real_mean[ch]) / double(n));
            plain_worst = std::max(plain_worst, std::abs(plain_mean[ch] - real_mean[ch]) / double(n));
        }
        CAPTURE(e);
        CHECK(worst < 1e-9);
        if (e != "neutral") CHECK(plain_worst > 0.5);  // without the correction the scaling moves the mean
    }
}

TEST_CASE("the checkpoint stores the ends anchor, transfer scales about it, and a bad field is refused by name")
{
    auto clips = toy_set();
    const fs::path d = fresh_dir("handemo_amplitude_anchor");
    auto o = handemo_options();
    o.iters = 3;
    o.threads = 1;
    o.progress_out = nullptr;
    o.gate_folds = 0;
    o.amplitude_anchor = "ends";
    CHECK(o.to_json().at("amplitude_anchor") == "ends");
    CHECK_FALSE(paper_options().to_json().contains("amplitude_anchor"));  // written only when not the mean
    CHECK(handemo_options().amplitude_anchor == "auto");
    auto bad = o;
    bad.amplitude_anchor = "median";
    CHECK_THROWS_WITH_AS(bad.validate(), "train: amplitude_anchor: amplitude anchor 'median' is not 'mean' or 'ends'", value_error);
    auto data = prepare_data<hand_tiny>(clips, tiny_info(), o);
    CHECK(data.amplitude_anchor == amplitude_anchor::ends);
    trainer<hand_tiny> tr(tiny_info(), std::move(data), o);
    tr.save(d);  // G at initialisation: the residual identity, so the output is the input's keyframes, scaled
    auto [f, info] = read_checkpoint(d / "checkpoint.safetensors");
    CHECK(info.amplitude_anchor == amplitude_anchor::ends);
    info.amplitude = {1.4, 0.7, 1.0, 0.8, 1.2};  // away from 1 whatever the toy set's check found
    const auto model = load_model(f, info);
    REQUIRE(model->amplitude_stage());
    const clip& in = clips[2].motion;
    const auto r = model->transfer(in, "angry");
    CHECK(r.amplitude_anchor == amplitude_anchor::ends);
    CHECK(r.amplitude == doctest::Approx(1.4));
    auto k = extract_keyframes<dynamic_keyframes>(in, 9), km = k;
    scale_keyframe_excursions(k, r.amplitude, amplitude_anchor::ends);
    scale_keyframe_excursions(km, r.amplitude);
    const clip expect = reconstruct(k, in.skel, r.motion.frames, in.fps), about_mean = reconstruct(km, in.skel, r.motion.frames, in.fps);
    double worst = 0, off = 0;
    for (std::size_t i = 0; i < expect.angles.size(); ++i) {
        worst = std::max(worst, std::abs(expect.angles[i] - r.motion.angles[i]));
        off = std::max(off, std::abs(about_mean.angles[i] - r.motion.angles[i]));
    }
    CHECK(worst < 1e-6);
    CHECK(off > 0.1);
    // statistics() takes the same anchor
    const auto s = model->statistics(in, "angry");
    CHECK(s.amplitude_anchor == amplitude_anchor::ends);
    CHECK(s.motion.angles == model->finish(in, model->parts(in, "angry"), 0, 0, 1).angles);

    // a checkpoint whose field is not "mean" or "ends" is refused, naming the file and the field
    auto j = nlohmann::json::parse(f.metadata.at("handemo"));
    j["amplitude_anchor"] = "middle";
    f.metadata["handemo"] = j.dump();
    f.metadata["checksum"] = stargan::detail::checkpoint_checksum(f);
    const fs::path broken = d / "broken.safetensors";
    write_safetensors(broken, f);
    CHECK_THROWS_WITH_AS(read_checkpoint(broken), doctest::Contains("metadata field 'amplitude_anchor' is \"middle\""), format_error);
    const std::string path = broken.string();
    CHECK_THROWS_WITH_AS(read_checkpoint(broken), doctest::Contains(path.c_str()), format_error);
    // a checkpoint without the field scales about the mean (every checkpoint written before the anchor existed)
    j.erase("amplitude_anchor");
    f.metadata["handemo"] = j.dump();
    f.metadata["checksum"] = stargan::detail::checkpoint_checksum(f);
    write_safetensors(broken, f);
    CHECK(read_checkpoint(broken).second.amplitude_anchor == amplitude_anchor::mean);
}

namespace {

/// 4 contents x {neutral, angry, fearful} x 2 takes, the amplitude_estimator cases' set: `moving` channels whose
/// movement each emotion scales exactly (scale_of()), the other channels held still with a wobble (capture noise)
/// that the emotion does not scale (twice as large in the emotional takes as in the neutral ones).
std::vector<labelled_clip> still_and_moving(std::size_t moving)
{
    std::vector<labelled_clip> out;
    for (int c = 0; c < 4; ++c)
        for (const char* e : {"neutral", "angry", "fearful"})
            for (int t = 0; t < 2; ++t) {
                const double s = scale_of(e), noise = std::string(e) == "neutral" ? 0.3 : 0.6;
                out.push_back(frames_clip("c" + std::to_string(c), e, std::to_string(t), [&](std::size_t k, std::size_t ch) {
                    const double base = 10.0 * std::sin(0.7 * double(ch) + double(c));
                    const double x = 2.0 * std::numbers::pi * 2.0 * double(k) / double(K - 1);
                    if (ch < moving) return base + s * (12.0 + 4.0 * std::cos(double(ch) + c)) * std::sin(x + 0.9 * double(ch) + 1.1 * c);
                    return base + noise * std::sin(1.7 * double(k) + double(ch) + 3.0 * t + 5.0 * c);
                }));
            }
    return out;
}

}  // namespace

TEST_CASE("amplitude estimator 'channel': the median ratio of the channels that move, blind to channels held still")
{
    // 8 channels move, the other 61 of the hand's 69 hold still with noise: the summed excursions' ratio mixes the
    // noise's ratio (2) into every emotion's factor, the moving channels' ratios are the scale exactly
    const auto clips = still_and_moving(8);
    const auto kfs = keys_of(clips);
    const std::vector<std::string> domains = {"angry", "fearful", "neutral"};
    for (auto anchor : {amplitude_anchor::mean, amplitude_anchor::ends}) {
        CAPTURE(anchor_name(anchor));
        const auto ch = amplitude_factors<K>(clips, kfs, domains, "neutral", anchor, amplitude_estimator::channel);
        CHECK(ch[0] == doctest::Approx(1.5).epsilon(1e-9));
        CHECK(ch[1] == doctest::Approx(0.8).epsilon(1e-9));
        CHECK(ch[2] == 1.0);
        const auto sum = amplitude_factors<K>(clips, kfs, domains, "neutral", anchor);  // the default: the sum
        CHECK(sum == amplitude_factors<K>(clips, kfs, domains, "neutral", anchor, amplitude_estimator::sum));
        CHECK(sum[1] > 0.9);  // fearful pulled toward (past) 1 by the still channels' noise
        CHECK(std::abs(sum[0] - 1.5) > 0.05);
    }
    // the per-channel excursions are the terms keyframe_excursion() sums
    for (auto anchor : {amplitude_anchor::mean, amplitude_anchor::ends}) {
        const auto e = channel_excursions(kfs[5], anchor);
        REQUIRE(e.size() == kfs[5].joints * 3);
        double total = 0;
        for (double v : e) total += v;
        CHECK(total == doctest::Approx(keyframe_excursion(kfs[5], anchor)).epsilon(1e-12));
    }
    // a channel that moves less than a tenth of the clip's largest is not counted: with most channels moving a
    // little (1/20 of the largest) and not scaled, the factor is still the scale of the large movements
    auto few = still_and_moving(3);
    for (auto& c : few) {
        const std::size_t C = c.motion.skel.size() * 3;
        for (std::size_t k = 0; k < K; ++k)
            for (std::size_t q = 3; q < C; ++q) c.motion.angles[k * C + q] += 0.8 * std::sin(2.0 * double(k) + double(q));
    }
    const auto f = amplitude_factors<K>(few, keys_of(few), domains, "neutral", amplitude_anchor::mean, amplitude_estimator::channel);
    CHECK(f[0] == doctest::Approx(1.5).epsilon(1e-9));
    CHECK(f[1] == doctest::Approx(0.8).epsilon(1e-9));
    // a domain without a neutral partner keeps 1
    std::vector<labelled_clip> only_c0;  // content c0's emotional takes, without its neutral ones
    for (const auto& c : clips)
        if (c.content == "c0" && c.emotion != "neutral") only_c0.push_back(c);
    const auto o = amplitude_factors<K>(only_c0, keys_of(only_c0), domains, "neutral", amplitude_anchor::mean, amplitude_estimator::channel);
    CHECK(o[0] == 1.0);
    CHECK(o[1] == 1.0);
}

TEST_CASE("amplitude estimator: fit_amplitude and the checks use it, the option is validated and written only when not the sum")
{
    const auto clips = still_and_moving(8);
    const auto kfs = keys_of(clips);
    const std::vector<std::string> domains = {"angry", "fearful", "neutral"};
    const auto r = fit_amplitude<K>(clips, kfs, domains, "neutral", "auto", amplitude_estimator::channel);
    REQUIRE(r.factors.size() == 3);
    CHECK(r.factors[1] == doctest::Approx(0.8).epsilon(1e-9));
    CHECK(r.anchor_check.first == amplitude_prior_cv<K>(clips, kfs, domains, "neutral", amplitude_anchor::mean, amplitude_estimator::channel).second);
    // on this set the moving channels' factors meet the left-out contents' takes closer than the summed ones
    CHECK(amplitude_prior_cv<K>(clips, kfs, domains, "neutral", amplitude_anchor::mean, amplitude_estimator::channel).second <
          amplitude_prior_cv<K>(clips, kfs, domains, "neutral", amplitude_anchor::mean).second);
    CHECK(amplitude_cv<K>(clips, kfs, domains, "neutral", amplitude_estimator::channel).second <
          amplitude_cv<K>(clips, kfs, domains, "neutral").second);

    train_options o = handemo_options();
    CHECK(o.amplitude_estimator == "sum");
    CHECK_FALSE(o.to_json().contains("amplitude_estimator"));  // written only when not the sum: older options stay equal
    o.amplitude_estimator = "channel";
    CHECK_NOTHROW(o.validate());
    CHECK(o.to_json().at("amplitude_estimator") == "channel");
    o.amplitude_estimator = "median";
    CHECK_THROWS_WITH_AS(o.validate(), "train: amplitude_estimator: amplitude estimator 'median' is not 'sum' or 'channel'", value_error);
    CHECK(parse_amplitude_estimator("channel", "x") == amplitude_estimator::channel);
    CHECK(std::string(estimator_name(amplitude_estimator::channel)) == "channel");
}
