// The baselines StarGAN emotion transfer (Section 3.4 of the hand paper) is measured against,
// computed on the same keyframes (Eq. 2) and training folds:
//   identity          output = input;
//   mean offset       output keyframes = input keyframes + delta_e, delta_e the training-set mean over
//                     (emotion e clip, neutral clip of the same content and take) pairs of the keyframe
//                     difference, each difference wrapped into (-180, 180] (the Eq. 3 image difference in
//                     degrees: the image is linear in the angle). Duration scaled by the same learned tempo
//                     factor as StarGAN's transfer, so both differ only in what they do to the keyframes;
//   nearest neighbour the training clip of the target emotion whose keyframes are closest (RMSE) to the input's.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/metrics/compare.hpp>
#include <handemo/motion/keyframes.hpp>
#include <handemo/motion/labelled.hpp>

#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace handemo::metrics {

/// @brief Identity baseline: the input, unchanged.
inline clip identity_baseline(const clip& in) { return in; }

/// @brief The mean-offset baseline fitted on a training set.
template <std::size_t K = 9>
class mean_offset_baseline {
public:
    /// @brief Fits delta_e for every non-neutral emotion of `train` (see the header comment).
    /// A clip whose content has no neutral take is skipped.
    /// @throws value_error when no clip of `train` is `neutral`.
    static mean_offset_baseline fit(const std::vector<labelled_clip>& train, const std::string& neutral)
    {
        mean_offset_baseline b;
        std::map<std::pair<std::string, std::string>, keyframes<K>> by_take;  // (content, take) -> neutral keyframes
        std::map<std::string, keyframes<K>> first;                           // content -> first neutral take
        for (const auto& c : train)
            if (c.emotion == neutral) {
                auto kf = extract_keyframes<K>(c.motion);
                by_take[{c.content, c.take}] = kf;
                if (!first.count(c.content)) first[c.content] = kf;
            }
        if (first.empty())
            throw value_error("mean_offset_baseline: no '" + neutral + "' clip in the training set (" + std::to_string(train.size()) +
                              " clips" + (train.empty() ? std::string() : ", the first " + train.front().path.string()) + ")");
        std::map<std::string, std::size_t> pairs;
        for (const auto& c : train) {
            if (c.emotion == neutral) continue;
            const keyframes<K>* base = nullptr;
            if (auto it = by_take.find({c.content, c.take}); it != by_take.end())
                base = &it->second;
            else if (auto f = first.find(c.content); f != first.end())
                base = &f->second;
            if (!base) continue;
            const auto kf = extract_keyframes<K>(c.motion);
            auto [it, fresh] = b.delta_.try_emplace(c.emotion, keyframes<K>::make(kf.joints, kf.count()));
            for (std::size_t i = 0; i < kf.angles.size(); ++i) it->second.angles[i] += wrap_degrees(kf.angles[i] - base->angles[i]);
            ++pairs[c.emotion];
        }
        for (auto& [e, d] : b.delta_)
            for (auto& v : d.angles) v /= static_cast<double>(pairs[e]);
        b.neutral_ = neutral;
        return b;
    }

    /// @brief Whether `emotion` is the neutral one or the training set had pairs of it.
    bool has(const std::string& emotion) const { return emotion == neutral_ || delta_.count(emotion) > 0; }

    /// @brief delta_e [K, J, 3] (zeros for the neutral emotion).
    /// @throws value_error for an emotion the training set had no pairs of.
    keyframes<K> delta(const std::string& emotion, std::size_t joints) const
    {
        if (emotion == neutral_) return keyframes<K>::make(joints);
        const auto it = delta_.find(emotion);
        if (it == delta_.end()) throw value_error("mean_offset_baseline: no training pairs of emotion '" + emotion + "'");
        if (it->second.joints != joints)
            throw shape_error("mean_offset_baseline: fitted on " + std::to_string(it->second.joints) + " joints, input has " +
                              std::to_string(joints));
        return it->second;
    }

    /// @brief Input keyframes + delta_e, reconstructed at round(frames x tempo) frames (Section 3.4).
    clip transfer(const clip& in, const std::string& emotion, double tempo = 1.0) const
    {
        auto kf = extract_keyframes<K>(in);
        const auto d = delta(emotion, kf.joints);
        for (std::size_t i = 0; i < kf.angles.size(); ++i) kf.angles[i] += d.angles[i];
        const auto frames = static_cast<std::size_t>(std::max(2.0, std::round(static_cast<double>(in.frames) * tempo)));
        clip out = reconstruct(kf, in.skel, frames, in.fps);
        out.positions = stretch_positions(in, frames);  // root translation stretched in time to the new length
        return out;
    }

private:
    std::map<std::string, keyframes<K>> delta_;
    std::string neutral_;
};

/// @brief Nearest-neighbour baseline: the index in `train` of the clip of emotion `target` whose K keyframes
/// are closest (keyframe_rmse) to the input's.
/// @throws value_error when `train` has no clip of `target`.
template <std::size_t K = 9>
std::size_t nearest_neighbour(const clip& in, const std::vector<labelled_clip>& train, const std::string& target)
{
    const auto kin = extract_keyframes<K>(in);
    std::size_t best = train.size();
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < train.size(); ++i) {
        if (train[i].emotion != target) continue;
        const double d = keyframe_rmse(kin, extract_keyframes<K>(train[i].motion));
        if (d < best_d) best_d = d, best = i;
    }
    if (best == train.size()) throw value_error("nearest_neighbour: no training clip of emotion '" + target + "'");
    return best;
}

}  // namespace handemo::metrics
