// The detail layer: what K keyframes cannot carry (Table 1's tremor, fine timing, the sharp turns of a fast
// motion), put back on a keyframe-spline output. A clip's *detail* is its full-rate residual about its own
// keyframe spline, r = unwrap(clip) - reconstruct(extract_keyframes<K>(clip)): zero at the first and last frame
// and (nearly) at every keyframe. Per emotion and channel the layer learns, from training clips only:
//   amplitude A[e][ch]  the mean RMS of r (degrees), and
//   frequency F[e]      the emotion's RMS frequency, sum RMS(dr/dt) / (2 pi sum RMS(r)) over clips and channels
//                       (Hz; exact for a sinusoid, amplitude-weighted otherwise).
// Applied to a transfer from emotion s to t, it takes the *input's own* detail (so a pushing hand keeps a
// pushing hand's fine motion), plays it back at F[t] / F[s] times its rate (looping: r is zero at both ends, so
// the loop is continuous), scales channel ch by A[t][ch] / A[s][ch], flattens it to zero at the output's keyframes
// (a short raised-cosine bump per keyframe, half a detail period wide) and adds it to the output. The output's
// keyframes, and so its keyframe RMSE and its recognised emotion, do not change; its full-rate range of motion and
// speed do.
// It cannot create detail on a channel where the input has none (A[s] near 0 gives gain 1 on a zero track).
// How far to trust the statistics is chosen inside the training set (fit_checked()): the gains and the rate are
// raised to a strength s in {0, 0.25, 0.5, 0.75, 1} (0: the input's detail as it is), the one whose outputs come
// closest to the real clips in full-rate range of motion and speed, leave-one-content-out on the training clips.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/keyframes.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace handemo {

namespace detail {
/// Full-rate range of motion and mean speed as eval/metrics.hpp measures them (angles taken within 180 degrees of the
/// first frame; speed on unwrapped angles), repeated here so the motion layer does not depend on the evaluation.
inline double range_of_motion_of(const clip& c)
{
    const std::size_t C = c.skel.size() * 3;
    double total = 0;
    for (std::size_t ch = 0; ch < C; ++ch) {
        double lo = 0, hi = 0;
        for (std::size_t f = 1; f < c.frames; ++f) {
            const double d = wrap_degrees(c.angles[f * C + ch] - c.angles[ch]);
            lo = std::min(lo, d), hi = std::max(hi, d);
        }
        total += hi - lo;
    }
    return C ? total / static_cast<double>(C) : 0.0;
}
inline double mean_speed_of(const clip& c)
{
    clip u = c;
    unwrap_angles(u);
    const std::size_t C = c.skel.size() * 3;
    double total = 0;
    for (std::size_t f = 1; f < u.frames; ++f)
        for (std::size_t ch = 0; ch < C; ++ch) total += std::abs(u.angles[f * C + ch] - u.angles[(f - 1) * C + ch]);
    return u.frames > 1 && C ? total * u.fps / static_cast<double>((u.frames - 1) * C) : 0.0;
}
}  // namespace detail

/// @brief The full-rate detail of `c` about its K-keyframe spline: [frames, J, 3] degrees (unwrapped clip minus
/// the Catmull-Rom spline through its uniform keyframes, the spline reconstruct() makes).
/// @throws value_error for fewer than 2 frames (extract_keyframes()).
template <std::size_t K = 9>
std::vector<double> detail_residual(const clip& c, std::size_t k = K)
{
    clip u = c;
    unwrap_angles(u);
    const clip s = reconstruct(extract_keyframes<K>(c, k), c.skel, c.frames, c.fps);
    std::vector<double> r(u.angles.size());
    for (std::size_t i = 0; i < r.size(); ++i) r[i] = u.angles[i] - s.angles[i];
    return r;
}

/// @brief Per channel RMS of a detail track (degrees) and of its rate of change (degrees per second).
struct detail_stats {
    std::vector<double> amplitude;  ///< [J*3] RMS of r
    std::vector<double> velocity;   ///< [J*3] RMS of dr/dt (backward differences x fps)
    /// @brief The RMS frequency over every channel, sum velocity / (2 pi sum amplitude), in Hz (0 for no detail).
    double frequency() const noexcept
    {
        double a = 0, v = 0;
        for (double x : amplitude) a += x;
        for (double x : velocity) v += x;
        return a > 0 ? v / (2 * std::numbers::pi * a) : 0.0;
    }
};

/// @brief The detail statistics of `c` (see detail_residual()).
template <std::size_t K = 9>
detail_stats measure_detail(const clip& c, std::size_t k = K)
{
    const auto r = detail_residual<K>(c, k);
    const std::size_t C = c.skel.size() * 3;
    detail_stats s;
    s.amplitude.assign(C, 0.0);
    s.velocity.assign(C, 0.0);
    for (std::size_t f = 0; f < c.frames; ++f)
        for (std::size_t ch = 0; ch < C; ++ch) {
            s.amplitude[ch] += r[f * C + ch] * r[f * C + ch];
            if (f > 0) {
                const double d = (r[f * C + ch] - r[(f - 1) * C + ch]) * c.fps;
                s.velocity[ch] += d * d;
            }
        }
    for (std::size_t ch = 0; ch < C; ++ch) {
        s.amplitude[ch] = std::sqrt(s.amplitude[ch] / static_cast<double>(c.frames));
        s.velocity[ch] = std::sqrt(s.velocity[ch] / static_cast<double>(c.frames - 1));
    }
    return s;
}

/// @brief Per-emotion detail statistics learned from training clips, and their application to an output.
struct detail_layer {
    /// Largest per-channel gain A[t]/A[s] and frequency ratio F[t]/F[s] (and smallest, 1/max): a channel with
    /// almost no detail in the source emotion would otherwise get an unbounded gain.
    static constexpr double max_gain = 4.0, max_rate = 4.0;

    std::size_t keyframes = 9;                     ///< K the residuals are taken about
    std::size_t channels = 0;                      ///< J*3
    std::vector<std::string> emotions;
    std::vector<std::vector<double>> amplitude;    ///< [E][J*3] mean RMS detail (degrees)
    std::vector<double> frequency;                 ///< [E] RMS frequency (Hz)
    std::vector<std::size_t> clips;                ///< [E] training clips behind each row
    /// Exponent of gain() and rate(): 1 the statistics as learned, 0 the input's own detail unchanged; chosen by
    /// fit_checked(), 1 after fit()
    double strength = 1.0;
    /// fit_checked()'s training-set check: per candidate strength (strength_candidates()), the mean over the
    /// held-out pairs of |log(ROM out / ROM real)| + |log(speed out / speed real)| (full rate); empty after fit()
    std::vector<double> check_error;

    /// The strengths fit_checked() chooses from.
    static constexpr std::array<double, 5> strength_candidates{0.0, 0.25, 0.5, 0.75, 1.0};

    /// @brief One training clip for fit_checked(): its motion, emotion, content (motion type) and take.
    struct sample {
        const clip* motion = nullptr;
        std::string emotion, content, take;
    };

    /// @brief fit(), with the strength chosen inside the training set: for every content, the layer fitted on the
    /// other contents puts the detail of each of this content's `neutral` takes on the keyframe spline of the same
    /// take in every other emotion (a perfect keyframe transfer), and the full-rate range of motion and speed of the
    /// result are compared with the real clip's; the candidate strength with the lowest mean error is kept (ties:
    /// the stronger). With fewer than 2 contents, or no pair, the strength stays 1.
    /// @throws as fit().
    static detail_layer fit_checked(const std::vector<sample>& data, const std::string& neutral, std::size_t k = 9)
    {
        std::vector<std::pair<const clip*, std::string>> all;
        for (const auto& d : data) all.push_back({d.motion, d.emotion});
        detail_layer m = fit(all, k);
        std::vector<std::string> contents;
        for (const auto& d : data)
            if (std::find(contents.begin(), contents.end(), d.content) == contents.end()) contents.push_back(d.content);
        if (contents.size() < 2) return m;
        std::vector<double> err(strength_candidates.size(), 0.0);
        std::size_t pairs = 0;
        for (const auto& c : contents) {
            std::vector<std::pair<const clip*, std::string>> rest;
            for (const auto& d : data)
                if (d.content != c) rest.push_back({d.motion, d.emotion});
            const detail_layer inner = fit(rest, k);
            for (const auto& in : data) {
                if (in.content != c || in.emotion != neutral) continue;
                for (const auto& real : data) {
                    if (real.content != c || real.take != in.take || real.emotion == neutral) continue;
                    if (std::find(inner.emotions.begin(), inner.emotions.end(), real.emotion) == inner.emotions.end() ||
                        std::find(inner.emotions.begin(), inner.emotions.end(), neutral) == inner.emotions.end())
                        continue;
                    const clip spline = reconstruct(extract_keyframes<dynamic_keyframes>(*real.motion, k), real.motion->skel,
                                                    real.motion->frames, real.motion->fps);
                    const double rom_real = detail::range_of_motion_of(*real.motion), speed_real = detail::mean_speed_of(*real.motion);
                    std::array<double, strength_candidates.size()> e{};
                    for (std::size_t i = 0; i < strength_candidates.size(); ++i) {
                        detail_layer l = inner;
                        l.strength = strength_candidates[i];
                        const clip out = l.apply(spline, *in.motion, neutral, real.emotion);
                        e[i] = std::abs(std::log(detail::range_of_motion_of(out) / rom_real)) + std::abs(std::log(detail::mean_speed_of(out) / speed_real));
                    }
                    // a motionless clip has no ratio to compare: the pair is left out (the check stays finite)
                    if (!std::all_of(e.begin(), e.end(), [](double x) { return std::isfinite(x); })) continue;
                    for (std::size_t i = 0; i < e.size(); ++i) err[i] += e[i];
                    ++pairs;
                }
            }
        }
        if (pairs == 0) return m;
        for (double& e : err) e /= static_cast<double>(pairs);
        std::size_t best = 0;
        for (std::size_t i = 1; i < err.size(); ++i)
            if (err[i] <= err[best]) best = i;
        m.strength = strength_candidates[best];
        m.check_error = err;
        return m;
    }

    /// @brief Learns the statistics from (clip, emotion) pairs, every clip of the same skeleton size.
    /// @throws value_error for no clips; shape_error when the skeletons differ in joint count.
    static detail_layer fit(const std::vector<std::pair<const clip*, std::string>>& data, std::size_t k = 9)
    {
        if (data.empty()) throw value_error("detail_layer::fit: no training clips");
        detail_layer m;
        m.keyframes = k;
        m.channels = data.front().first->skel.size() * 3;
        std::vector<double> vsum, asum;
        for (const auto& [c, e] : data) {
            if (c->skel.size() * 3 != m.channels)
                throw shape_error("detail_layer::fit: clip " + c->skel.name + " has " + std::to_string(c->skel.size()) + " joints, expected " +
                                  std::to_string(m.channels / 3));
            auto it = std::find(m.emotions.begin(), m.emotions.end(), e);
            const auto d = static_cast<std::size_t>(it - m.emotions.begin());
            if (it == m.emotions.end()) {
                m.emotions.push_back(e);
                m.amplitude.emplace_back(m.channels, 0.0);
                m.clips.push_back(0);
                vsum.push_back(0), asum.push_back(0);
            }
            const auto s = measure_detail<dynamic_keyframes>(*c, k);
            for (std::size_t ch = 0; ch < m.channels; ++ch) {
                m.amplitude[d][ch] += s.amplitude[ch];
                asum[d] += s.amplitude[ch];
                vsum[d] += s.velocity[ch];
            }
            ++m.clips[d];
        }
        m.frequency.resize(m.emotions.size());
        for (std::size_t d = 0; d < m.emotions.size(); ++d) {
            for (double& a : m.amplitude[d]) a /= static_cast<double>(m.clips[d]);
            m.frequency[d] = asum[d] > 0 ? vsum[d] / (2 * std::numbers::pi * asum[d]) : 0.0;
        }
        return m;
    }

    /// @brief Index of an emotion. @throws value_error naming it and the known ones.
    std::size_t index(const std::string& emotion) const
    {
        const auto it = std::find(emotions.begin(), emotions.end(), emotion);
        if (it == emotions.end()) {
            std::string known;
            for (const auto& e : emotions) known += (known.empty() ? "" : ", ") + e;
            throw value_error("detail layer: emotion '" + emotion + "' has no statistics (known: " + known + ")");
        }
        return static_cast<std::size_t>(it - emotions.begin());
    }

    /// @brief Rate at which the input's detail is played back for a transfer source -> target: F[t] / F[s],
    /// within [1/max_rate, max_rate], to the power `strength`; 1 when either emotion has no detail.
    double rate(const std::string& source, const std::string& target) const
    {
        const double fs = frequency[index(source)], ft = frequency[index(target)];
        if (!(fs > 0) || !(ft > 0)) return 1.0;
        return std::pow(std::clamp(ft / fs, 1.0 / max_rate, max_rate), strength);
    }

    /// @brief Gain of channel `ch` for source -> target: A[t][ch] / A[s][ch] within [0, max_gain], to the power
    /// `strength`; 1 where the source has (almost) no detail (1e-6 deg).
    double gain(const std::string& source, const std::string& target, std::size_t ch) const
    {
        const auto& a_s = amplitude[index(source)];
        const auto& a_t = amplitude[index(target)];
        if (ch >= a_s.size() || ch >= a_t.size())
            throw value_error("detail layer: channel " + std::to_string(ch) + " out of range (" + std::to_string(a_s.size()) + " channels)");
        const double as = a_s[ch], at = a_t[ch];
        if (!(as > 1e-6)) return 1.0;
        return std::pow(std::clamp(at / as, 0.0, max_gain), strength);
    }

    /// @brief `out` (a keyframe-spline output of a transfer of `input` from `source` to `target`) with the input's
    /// detail added: played back at rate(), scaled by gain() per channel, zero at `out`'s keyframes (as
    /// extract_keyframes() samples them: exactly, whenever the keyframes are at least 2 frames apart).
    /// @throws shape_error when the clips' joint counts are not the layer's; value_error for an unknown emotion or
    ///         a clip of fewer than 2 frames.
    clip apply(const clip& out, const clip& input, const std::string& source, const std::string& target) const
    {
        if (input.skel.size() * 3 != channels || out.skel.size() * 3 != channels)
            throw shape_error("detail layer: clips have " + std::to_string(input.skel.size()) + " and " + std::to_string(out.skel.size()) +
                              " joints, the layer was learned on " + std::to_string(channels / 3));
        if (out.frames < 2) throw value_error("detail layer: output of " + std::to_string(out.frames) + " frames");
        const auto r = detail_residual<dynamic_keyframes>(input, keyframes);
        const double rho = rate(source, target);
        std::vector<double> g(channels);
        for (std::size_t ch = 0; ch < channels; ++ch) g[ch] = gain(source, target, ch);
        // the input's detail at rho times its rate, looped (r is 0 at both ends)
        const double span = static_cast<double>(input.frames - 1);
        clip d = clip::make(out.skel, out.frames, out.fps);
        for (std::size_t f = 0; f < out.frames; ++f) {
            double pos = std::fmod(static_cast<double>(f) / out.fps * rho * input.fps, span);
            const auto f0 = std::min(static_cast<std::size_t>(pos), input.frames - 2);
            const double a = pos - static_cast<double>(f0);
            for (std::size_t ch = 0; ch < channels; ++ch)
                d.angles[f * channels + ch] = g[ch] * ((1 - a) * r[f0 * channels + ch] + a * r[(f0 + 1) * channels + ch]);
        }
        // Zero at the output's keyframes, so they (and all that is measured on them) stay: at each keyframe position
        // p (fractional, as extract_keyframes() samples), a short raised-cosine bump scaled to the detail's value
        // there is subtracted. Its half-width is half a period of the played-back detail (in [2 frames, half the
        // keyframe spacing]), so it flattens the detail locally and adds no slow wave, unlike subtracting a spline
        // through the detail's keyframe values would.
        const std::size_t K = keyframes;
        const double spacing = static_cast<double>(out.frames - 1) / static_cast<double>(K - 1);
        const double f_out = frequency[index(target)];
        double h = f_out > 0 ? 0.5 * out.fps / f_out : spacing / 2;
        h = std::clamp(h, std::min(2.0, spacing / 2), spacing / 2);
        const auto bump = [&](double x) { return std::abs(x) < h ? std::pow(std::cos(std::numbers::pi * x / (2 * h)), 2) : 0.0; };
        clip res = out;
        for (std::size_t i = 0; i < K; ++i) {
            const double p = static_cast<double>(i) * spacing;
            const auto f0 = std::min(static_cast<std::size_t>(p), out.frames - 2);
            const double a = p - static_cast<double>(f0);
            const double at_p = (1 - a) * bump(static_cast<double>(f0) - p) + a * bump(static_cast<double>(f0 + 1) - p);  // >= 1/2
            const auto lo = static_cast<std::size_t>(std::max(0.0, std::ceil(p - h))), hi = std::min(out.frames - 1, static_cast<std::size_t>(p + h));
            for (std::size_t ch = 0; ch < channels; ++ch) {
                const double dp = (1 - a) * d.angles[f0 * channels + ch] + a * d.angles[(f0 + 1) * channels + ch];
                if (dp == 0 || !(at_p > 1e-9)) continue;
                const double s = dp / at_p;
                for (std::size_t f = lo; f <= hi; ++f) res.angles[f * channels + ch] -= s * bump(static_cast<double>(f) - p);
            }
        }
        for (std::size_t i = 0; i < res.angles.size(); ++i) res.angles[i] += d.angles[i];
        return res;
    }

    /// @brief The layer as JSON (`format` handemo-detail/1).
    nlohmann::json to_json() const
    {
        nlohmann::json j;
        j["format"] = "handemo-detail/1";
        j["keyframes"] = keyframes;
        j["channels"] = channels;
        j["emotions"] = emotions;
        j["amplitude"] = amplitude;
        j["frequency"] = frequency;
        j["clips"] = clips;
        j["strength"] = strength;
        if (!check_error.empty()) j["check_error"] = check_error;
        return j;
    }

    /// @brief Reads a layer written by to_json(). `what` names the source (a file, a checkpoint field) in errors.
    /// @throws format_error naming `what` and the field for a missing, mistyped or out-of-range value.
    static detail_layer from_json(const nlohmann::json& j, const std::string& what)
    {
        const auto fail = [&](const std::string& m) { return format_error(what + ": detail layer: " + m); };
        if (!j.is_object()) throw fail("is not a JSON object");
        detail_layer m;
        try {
            if (j.at("format") != "handemo-detail/1") throw fail("format " + j.at("format").dump() + " is not handemo-detail/1");
            const auto count = [&](const char* key, std::uint64_t lo, std::uint64_t hi) {
                const auto& v = j.at(key);
                if (!v.is_number_unsigned() || v.get<std::uint64_t>() < lo || v.get<std::uint64_t>() > hi)
                    throw fail(std::string("field '") + key + "' is " + v.dump() + ", expected an integer in " + std::to_string(lo) + ".." +
                               std::to_string(hi));
                return static_cast<std::size_t>(v.get<std::uint64_t>());
            };
            m.keyframes = count("keyframes", 2, 1u << 16);
            m.channels = count("channels", 3, 3u << 16);
            m.emotions = j.at("emotions").get<std::vector<std::string>>();
            m.amplitude = j.at("amplitude").get<std::vector<std::vector<double>>>();
            m.frequency = j.at("frequency").get<std::vector<double>>();
            if (j.contains("strength")) m.strength = j.at("strength").get<double>();
            if (j.contains("check_error")) m.check_error = j.at("check_error").get<std::vector<double>>();
            // integers only from JSON integers: a float such as 1e300 converted to an integer type is undefined
            for (const auto& v : j.at("clips")) {
                if (!v.is_number_unsigned() || v.get<std::uint64_t>() > (std::uint64_t{1} << 32))
                    throw fail("field 'clips' holds " + v.dump() + ", expected clip counts");
                m.clips.push_back(static_cast<std::size_t>(v.get<std::uint64_t>()));
            }
        } catch (const nlohmann::json::exception& e) {
            throw fail(std::string("malformed: ") + e.what());
        }
        const std::size_t E = m.emotions.size();
        if (E == 0) throw fail("no emotions");
        if (!(m.strength >= 0 && m.strength <= 1)) throw fail("field 'strength' is not in [0, 1]");
        if (m.amplitude.size() != E || m.frequency.size() != E || m.clips.size() != E)
            throw fail("amplitude, frequency and clips have " + std::to_string(m.amplitude.size()) + ", " + std::to_string(m.frequency.size()) +
                       " and " + std::to_string(m.clips.size()) + " rows for " + std::to_string(E) + " emotions");
        for (std::size_t d = 0; d < E; ++d) {
            if (m.amplitude[d].size() != m.channels)
                throw fail("amplitude of '" + m.emotions[d] + "' has " + std::to_string(m.amplitude[d].size()) + " channels, expected " +
                           std::to_string(m.channels));
            for (double a : m.amplitude[d])
                if (!(a >= 0 && a <= 360)) throw fail("amplitude of '" + m.emotions[d] + "' has a value outside [0, 360] deg");
            if (!(m.frequency[d] >= 0 && m.frequency[d] <= 1000)) throw fail("frequency of '" + m.emotions[d] + "' is outside [0, 1000] Hz");
        }
        return m;
    }
};

}  // namespace handemo
