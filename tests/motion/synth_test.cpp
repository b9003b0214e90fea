#include <handemo/motion/bvh.hpp>
#include <handemo/motion/codec.hpp>
#include <handemo/motion/keyframes.hpp>
#include <handemo/motion/synth.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <map>

using namespace handemo;

namespace {
const std::vector<synth_item>& dataset()
{
    static const std::vector<synth_item> d = synthesize_dataset(3, 2024);
    return d;
}

// Sum over rotation channels of the range of motion, after a 7-frame moving average (removes tremor).
double smoothed_range(const clip& c)
{
    const std::size_t J3 = c.skel.size() * 3;
    double total = 0;
    for (std::size_t i = 0; i < J3; ++i) {
        double lo = 1e9, hi = -1e9;
        for (std::size_t f = 0; f < c.frames; ++f) {
            double s = 0;
            int n = 0;
            for (int d = -3; d <= 3; ++d) {
                const long g = static_cast<long>(f) + d;
                if (g < 0 || g >= static_cast<long>(c.frames)) continue;
                s += c.angles[static_cast<std::size_t>(g) * J3 + i];
                ++n;
            }
            lo = std::min(lo, s / n);
            hi = std::max(hi, s / n);
        }
        total += hi - lo;
    }
    return total;
}

// Spread (cycles) of the phase lags of index..pinky MCP flexion, by circular cross-correlation over the
// two periodic cycles (the clip's frames 0..n-2 cover exactly 2 cycles).
double finger_phase_spread(const clip& c)
{
    const std::size_t n = c.frames - 1;
    auto sig = [&](std::size_t f) {
        std::vector<double> s(n);
        double m = 0;
        for (std::size_t i = 0; i < n; ++i) m += s[i] = c.angle(i, hand_index::finger_joint(f, 1), 0);
        for (auto& v : s) v -= m / static_cast<double>(n);
        return s;
    };
    const auto ref = sig(1);
    double lo = 0, hi = 0;
    for (std::size_t f = 2; f < 5; ++f) {
        const auto s = sig(f);
        long best = 0;
        double best_v = -1e300;
        const long half = static_cast<long>(n / 4);
        for (long lag = -half; lag <= half; ++lag) {
            double v = 0;
            for (std::size_t i = 0; i < n; ++i) v += s[(i + n + static_cast<std::size_t>(lag + static_cast<long>(n))) % n] * ref[i];
            if (v > best_v) best_v = v, best = lag;
        }
        const double cyc = static_cast<double>(best) * synth_cycles / static_cast<double>(n);
        lo = std::min(lo, cyc);
        hi = std::max(hi, cyc);
    }
    return hi - lo;
}
}  // namespace

TEST_CASE("synth: names, file stems and their errors")
{
    for (emotion e : all_emotions) CHECK(emotion_from_string(to_string(e)) == e);
    for (hand_motion m : all_hand_motions) CHECK(hand_motion_from_string(to_string(m)) == m);
    CHECK(to_string(hand_motion::hand_on_mouse) == "hand-on-mouse");
    CHECK_THROWS_AS(emotion_from_string("bored"), value_error);
    CHECK_THROWS_AS(hand_motion_from_string("swimming"), value_error);
    CHECK(file_stem(hand_motion::hand_on_mouse, emotion::sad, 3) == "hand_hand-on-mouse_sad_3");
    const auto l = parse_file_stem("hand_hand-on-mouse_sad_3");
    CHECK(l.motion == hand_motion::hand_on_mouse);
    CHECK(l.emo == emotion::sad);
    CHECK(l.take == 3);
    try {
        (void)parse_file_stem("hand_crawling_bored_0");
        FAIL("no error");
    } catch (const value_error& e) {
        CHECK(std::string(e.what()).find("bored") != std::string::npos);
    }
    CHECK_THROWS_AS(parse_file_stem("hand_crawling_sad"), value_error);
    CHECK_THROWS_AS(parse_file_stem("hand_crawling_sad_x"), value_error);
    CHECK_THROWS_AS(synthesize(hand_motion::crawling, emotion::sad, 0, 1, 0.0), value_error);
    CHECK_THROWS_AS(synthesize_dataset(0, 1), value_error);
}

TEST_CASE("synth: deterministic per seed, different per take and seed, within limits, 2 cycles")
{
    const clip a = synthesize(hand_motion::gripping, emotion::happy, 1, 7);
    const clip b = synthesize(hand_motion::gripping, emotion::happy, 1, 7);
    CHECK(a.angles == b.angles);
    CHECK(a.positions == b.positions);
    CHECK(synthesize(hand_motion::gripping, emotion::happy, 2, 7).angles != a.angles);
    CHECK(synthesize(hand_motion::gripping, emotion::happy, 1, 8).angles != a.angles);
    const auto& d = dataset();
    REQUIRE(d.size() == 7 * 5 * 3);
    for (const auto& it : d) {
        CHECK_NOTHROW(it.c.validate(it.file_stem));
        CHECK(it.c.joint_count() == hand_joint_count);
        CHECK(it.c.fps == 60.0);
        CHECK(it.file_stem == file_stem(it.motion, it.emo, it.take));
        for (std::size_t f = 0; f < it.c.frames; ++f)
            for (std::size_t j = 0; j < 23; ++j)
                for (std::size_t k = 0; k < 3; ++k) {
                    const double v = it.c.angle(f, j, k);
                    if (v < it.c.skel.joints[j].lower_limit[k] || v > it.c.skel.joints[j].upper_limit[k])
                        FAIL(it.file_stem << " frame " << f << " joint " << j << " axis " << k << " = " << v);
                }
        if (it.emo == emotion::neutral) {
            CHECK(it.c.duration() >= 1.9);
            CHECK(it.c.duration() <= 4.0);
        }
        // Exactly 2 cycles: after a 7-frame moving average (removes tremor), the clip shifted by one cycle
        // matches itself better than shifted by any fraction of a cycle.
        const std::size_t cyc = (it.c.frames - 1) / 2, J3 = 69;
        std::vector<double> sm(it.c.angles.size());
        for (std::size_t f = 0; f < it.c.frames; ++f)
            for (std::size_t i = 0; i < J3; ++i) {
                double s = 0;
                int cnt = 0;
                for (long g = static_cast<long>(f) - 3; g <= static_cast<long>(f) + 3; ++g)
                    if (g >= 0 && g < static_cast<long>(it.c.frames)) s += it.c.angles[static_cast<std::size_t>(g) * J3 + i], ++cnt;
                sm[f * J3 + i] = s / cnt;
            }
        std::vector<std::size_t> active;  // channels that really move (> 3 deg after smoothing)
        for (std::size_t i = 0; i < J3; ++i) {
            double lo = 1e9, hi = -1e9;
            for (std::size_t f = 0; f < it.c.frames; ++f) lo = std::min(lo, sm[f * J3 + i]), hi = std::max(hi, sm[f * J3 + i]);
            if (hi - lo > 3.0) active.push_back(i);
        }
        REQUIRE_MESSAGE(!active.empty(), it.file_stem);
        auto shifted = [&](double s) {
            const auto sh = static_cast<std::size_t>(std::lround(s * static_cast<double>(cyc)));
            double d = 0;
            for (std::size_t f = 0; f < cyc; ++f)
                for (std::size_t i : active) d += std::abs(sm[f * J3 + i] - sm[(f + sh) * J3 + i]);
            return d;
        };
        const double one = shifted(1.0);
        for (double s : {0.2, 0.35, 0.5, 0.65, 0.8}) CHECK_MESSAGE(one < shifted(s), it.file_stem << " shift " << s);
    }
}

TEST_CASE("synth: per-emotion statistics follow Table 1")
{
    std::map<emotion, double> rom, dur, spread;
    std::map<hand_motion, std::map<emotion, double>> rom_m;
    for (const auto& it : dataset()) {
        const double r = smoothed_range(it.c);
        rom[it.emo] += r;
        rom_m[it.motion][it.emo] += r;
        dur[it.emo] += it.c.duration();
        if (it.motion == hand_motion::gripping) spread[it.emo] += finger_phase_spread(it.c) / 3.0;
    }
    for (emotion e : all_emotions)
        MESSAGE(to_string(e) << ": range of motion " << rom[e] / 21 << " deg (sum over channels), duration " << dur[e] / 21
                             << " s, finger phase spread (gripping) " << spread[e] << " cycles");
    // angry: exaggerated, fast, large range; happy: energetic, large; sad: tired, slow, small; fearful: small.
    CHECK(rom[emotion::angry] > rom[emotion::happy]);
    CHECK(rom[emotion::happy] > 1.15 * rom[emotion::neutral]);
    CHECK(rom[emotion::sad] < 0.75 * rom[emotion::neutral]);
    CHECK(rom[emotion::fearful] < 0.85 * rom[emotion::neutral]);
    for (auto& [m, r] : rom_m) {
        CHECK_MESSAGE(r[emotion::angry] > r[emotion::neutral], to_string(m));
        CHECK_MESSAGE(r[emotion::neutral] > r[emotion::sad], to_string(m));
    }
    CHECK(dur[emotion::angry] < dur[emotion::happy]);
    CHECK(dur[emotion::happy] < dur[emotion::neutral]);
    CHECK(dur[emotion::neutral] < dur[emotion::sad]);
    // Asynchronous fingers only when fearful.
    CHECK(spread[emotion::fearful] > 0.15);
    for (emotion e : {emotion::angry, emotion::happy, emotion::neutral, emotion::sad}) CHECK_MESSAGE(spread[e] < 0.06, to_string(e));
    // The API returns the same ground truth.
    CHECK(style_of(emotion::sad).tempo < style_of(emotion::neutral).tempo);
    CHECK(style_of(emotion::fearful).phase_lag > 0);
}

TEST_CASE("synth: motion types are distinct movements (nearest-centroid on keyframe images)")
{
    const auto& d = dataset();
    std::vector<keyframes<9>> kf;
    for (const auto& it : d) kf.push_back(extract_keyframes<9>(it.c));
    const angle_range r = compute_range(kf);
    std::vector<std::vector<double>> x;
    for (const auto& k : kf) {
        const auto px = encode(k, r);
        x.emplace_back(px.values.begin(), px.values.end());
    }
    // Leave-one-out nearest centroid over the 7 motion types.
    int correct = 0;
    for (std::size_t q = 0; q < d.size(); ++q) {
        std::vector<std::vector<double>> cen(7, std::vector<double>(x[0].size(), 0.0));
        std::vector<int> cnt(7, 0);
        for (std::size_t i = 0; i < d.size(); ++i) {
            if (i == q) continue;
            const auto m = static_cast<std::size_t>(d[i].motion);
            for (std::size_t e = 0; e < x[i].size(); ++e) cen[m][e] += x[i][e];
            ++cnt[m];
        }
        std::size_t best = 0;
        double best_d = 1e300;
        for (std::size_t m = 0; m < 7; ++m) {
            double dist = 0;
            for (std::size_t e = 0; e < x[q].size(); ++e) {
                const double v = x[q][e] - cen[m][e] / cnt[m];
                dist += v * v;
            }
            if (dist < best_d) best_d = dist, best = m;
        }
        correct += best == static_cast<std::size_t>(d[q].motion);
        if (best != static_cast<std::size_t>(d[q].motion)) MESSAGE(d[q].file_stem << " classified as " << to_string(static_cast<hand_motion>(best)));
    }
    const double acc = static_cast<double>(correct) / static_cast<double>(d.size());
    MESSAGE("leave-one-out nearest-centroid motion-type accuracy: " << acc << " (" << correct << "/" << d.size() << ")");
    CHECK(acc >= 0.95);
    // The neutral keyframe images of different motion types are far apart (mean pixel distance).
    for (std::size_t a = 0; a < 7; ++a)
        for (std::size_t b = a + 1; b < 7; ++b) {
            const std::size_t ia = a * 15 + 2 * 3, ib = b * 15 + 2 * 3;  // neutral take 0
            double dist = 0;
            for (std::size_t e = 0; e < x[ia].size(); ++e) dist += std::abs(x[ia][e] - x[ib][e]);
            CHECK_MESSAGE(dist / static_cast<double>(x[ia].size()) > 2.0, a << " vs " << b);
        }
}

namespace {
// RMSE in degrees over the 9 uniform keyframes (synthetic angles stay within joint limits: no wrapping).
double keyframe_distance(const clip& a, const clip& b)
{
    const auto ka = extract_keyframes<9>(a), kb = extract_keyframes<9>(b);
    REQUIRE(ka.angles.size() == kb.angles.size());
    double s = 0;
    for (std::size_t i = 0; i < ka.angles.size(); ++i) s += (ka.angles[i] - kb.angles[i]) * (ka.angles[i] - kb.angles[i]);
    return std::sqrt(s / static_cast<double>(ka.angles.size()));
}
}  // namespace

TEST_CASE("synth: synthesize_as keeps the input take's variation and takes the target's style")
{
    for (hand_motion m : all_hand_motions)
        for (int take = 0; take < 2; ++take) {
            // neutral -> neutral: the oracle is the neutral take itself, bit for bit
            const clip in = synthesize(m, emotion::neutral, take, 2024);
            const clip same = synthesize_as(m, emotion::neutral, emotion::neutral, take, 2024);
            CHECK(same.frames == in.frames);
            CHECK(same.angles == in.angles);
            CHECK(same.positions == in.positions);
        }
    // Against the real emotional take, the oracle (same style, the neutral take's variation) is closer on
    // average than the neutral input: only per-take variation separates it from the real clip.
    double oracle = 0, input = 0;
    int n = 0;
    for (hand_motion m : all_hand_motions)
        for (emotion e : all_emotions) {
            if (e == emotion::neutral) continue;
            for (int take = 0; take < 3; ++take) {
                const clip in = synthesize(m, emotion::neutral, take, 2024);
                const clip real = synthesize(m, e, take, 2024);
                const clip orc = synthesize_as(m, emotion::neutral, e, take, 2024);
                CHECK(orc.fps == real.fps);
                // the target's tempo with the input take's jitter: within the jitter range of the real duration
                CHECK(orc.duration() / real.duration() == doctest::Approx(1.0).epsilon(0.16));
                oracle += keyframe_distance(orc, real), input += keyframe_distance(in, real), ++n;
            }
        }
    oracle /= n, input /= n;
    MESSAGE("synth oracle: mean keyframe RMSE to the real take " << oracle << " deg, neutral input " << input << " deg");
    CHECK(oracle < input);
    CHECK_THROWS_WITH_AS(synthesize_as(hand_motion::patting, emotion::neutral, emotion::sad, 0, 1, -1.0),
                         doctest::Contains("synthesize_as: fps"), value_error);
}

namespace {
// FNV-1a (64 bits) of the synthetic set as `handemo synth` writes it: every take's file stem and BVH text.
std::uint64_t bvh_hash(const std::vector<synth_item>& set)
{
    std::uint64_t h = 14695981039346656037ULL;
    auto add = [&](const std::string& s) {
        for (const unsigned char ch : s) h = (h ^ ch) * 1099511628211ULL;
    };
    for (const auto& it : set) add(it.file_stem), add(to_bvh_string(it.c));
    return h;
}
}  // namespace

TEST_CASE("synth: the 7-type set is byte for byte what it was for its seed and options")
{
    // The hashes were taken from the generator before the extended motion types were added (2 takes, seed 1,
    // 60 fps: `handemo synth --takes 2`; 1 take, seed 2024, 30 fps).
    const std::uint64_t h1 = bvh_hash(synthesize_dataset(2, 1, 60.0)), h2 = bvh_hash(synthesize_dataset(1, 2024, 30.0));
    MESSAGE("synth: hashes " << h1 << " " << h2);
    CHECK(h1 == 0xa406cbc768309049ULL);
    CHECK(h2 == 0x2f21dba4a111422eULL);
}

TEST_CASE("synth: the extended set, 12 motion types, the paper's 7 first and unchanged")
{
    CHECK(motions_of(motion_set::paper).size() == 7);
    CHECK(motions_of(motion_set::extended).size() == 12);
    CHECK(motion_set_from_string("extended") == motion_set::extended);
    CHECK(motion_set_from_string(to_string(motion_set::paper)) == motion_set::paper);
    CHECK_THROWS_WITH_AS(motion_set_from_string("all"), doctest::Contains("paper (7 motion types) or extended (12)"), value_error);
    for (hand_motion m : extended_hand_motions) {
        CHECK(hand_motion_from_string(to_string(m)) == m);
        CHECK(parse_file_stem(file_stem(m, emotion::sad, 2)).motion == m);
    }
    const auto paper = synthesize_dataset(1, 8, 30.0), ext = synthesize_dataset(1, 8, 30.0, motion_set::extended);
    REQUIRE(ext.size() == 60);
    for (std::size_t i = 0; i < paper.size(); ++i) {
        CHECK(ext[i].file_stem == paper[i].file_stem);
        CHECK(ext[i].c.angles == paper[i].c.angles);
        CHECK(ext[i].c.positions == paper[i].c.positions);
    }
    // the paper's seven show the table as it is, bit for bit
    for (hand_motion m : all_hand_motions)
        for (emotion e : all_emotions) {
            const auto a = style_of(m, e), b = style_of(e);
            CHECK(a.tempo == b.tempo);
            CHECK(a.amplitude == b.amplitude);
            CHECK(a.droop_deg == b.droop_deg);
            CHECK(a.tremor_deg == b.tremor_deg);
            CHECK(a.phase_lag == b.phase_lag);
        }
    // the new types: within limits, exactly 2 cycles, each its own movement (its neutral takes closer to each other than
    // to any other type's)
    for (std::size_t i = 35; i < ext.size(); ++i) {
        const auto& it = ext[i];
        for (std::size_t f = 0; f < it.c.frames; ++f)
            for (std::size_t j = 0; j < it.c.skel.size(); ++j)
                for (std::size_t a = 0; a < 3; ++a) {
                    CHECK(it.c.angle(f, j, a) >= it.c.skel.joints[j].lower_limit[a]);
                    CHECK(it.c.angle(f, j, a) <= it.c.skel.joints[j].upper_limit[a]);
                }
        const double expect = synth_cycles * neutral_period(it.motion) / style_of(it.motion, it.emo).tempo;
        CHECK(it.c.duration() == doctest::Approx(expect).epsilon(0.08));
    }
    for (hand_motion m : extended_hand_motions) {
        if (static_cast<std::size_t>(m) < hand_motion_count) continue;
        const clip a = synthesize(m, emotion::neutral, 0, 8), b = synthesize(m, emotion::neutral, 1, 8);
        const double same = keyframe_distance(a, b);
        for (hand_motion o : extended_hand_motions)
            if (o != m) CHECK_MESSAGE(keyframe_distance(a, synthesize(o, emotion::neutral, 0, 8)) > same, to_string(m) << " vs " << to_string(o));
    }
}

TEST_CASE("synth: the extended types show each emotion effect as their gains say")
{
    for (hand_motion m : extended_hand_motions) {
        if (static_cast<std::size_t>(m) < hand_motion_count) continue;
        const auto g = expression_of(m);
        double dur[emotion_count] = {}, rom[emotion_count] = {};
        for (emotion e : all_emotions)
            for (int take = 0; take < 3; ++take) {
                const clip c = synthesize(m, e, take, 2024);
                dur[static_cast<int>(e)] += c.duration() / 3, rom[static_cast<int>(e)] += smoothed_range(c) / 3;
            }
        const auto d = [&](emotion e) { return dur[static_cast<int>(e)]; };
        const auto r = [&](emotion e) { return rom[static_cast<int>(e)]; };
        // tempo: sad lasts 1 / 0.6^power as long as neutral (per-take jitter 7%), angry 1 / 1.6^power
        CHECK_MESSAGE(d(emotion::sad) / d(emotion::neutral) == doctest::Approx(std::pow(0.6, -g.tempo)).epsilon(0.08), to_string(m));
        CHECK_MESSAGE(d(emotion::angry) / d(emotion::neutral) == doctest::Approx(std::pow(1.6, -g.tempo)).epsilon(0.08), to_string(m));
        // amplitude: angry's excursions larger than neutral's, sad's smaller
        CHECK_MESSAGE(r(emotion::angry) > r(emotion::neutral), to_string(m));
        CHECK_MESSAGE(r(emotion::sad) < r(emotion::neutral), to_string(m));
        // the styles themselves
        CHECK(style_of(m, emotion::sad).tempo == doctest::Approx(std::pow(0.6, g.tempo)));
        CHECK(style_of(m, emotion::angry).amplitude == doctest::Approx(std::pow(1.45, g.amplitude)));
        CHECK(style_of(m, emotion::sad).droop_deg == doctest::Approx(12 * g.droop));
        CHECK(style_of(m, emotion::fearful).tremor_deg == doctest::Approx(1.0 * g.tremor));
        CHECK(style_of(m, emotion::fearful).phase_lag == doctest::Approx(0.09 * g.lag));
    }
    // finger lag: under fear, counting (lag x 2) moves its fingers' phases apart from their calm sequence (either way)
    const clip fear = synthesize(hand_motion::counting, emotion::fearful, 0, 2024), calm = synthesize(hand_motion::counting, emotion::neutral, 0, 2024);
    CHECK(std::abs(finger_phase_spread(fear) - finger_phase_spread(calm)) > 0.1);
}
