// Helpers shared by the StarGAN test programs (train_test, dataset_test, shared_data_test).
#pragma once

#include <doctest/doctest.h>
#include <handemo/motion/synth.hpp>
#include <handemo/stargan.hpp>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

namespace handemo::test {

/// A toy set: 3 motion types (gripping, patting, pointing) x 5 emotions x 1 take of the synthetic hand data
/// (`seed`, `fps`), as labelled clips.
inline std::vector<handemo::labelled_clip> toy_set(std::uint64_t seed = 7, double fps = 60.0)
{
    std::vector<handemo::labelled_clip> out;
    for (auto& it : synthesize_dataset(1, seed, fps)) {
        if (it.motion != hand_motion::gripping && it.motion != hand_motion::patting && it.motion != hand_motion::pointing)
            continue;
        handemo::labelled_clip c;
        c.path = it.file_stem + ".bvh";
        const auto n = stargan::parse_clip_name(it.file_stem);
        c.content = n.content;
        c.emotion = n.emotion;
        c.take = n.take;
        c.motion = it.c;
        out.push_back(std::move(c));
    }
    return out;
}

inline stargan::config_info tiny_info() { return stargan::make_info<stargan::hand_tiny>("hand-tiny", stargan::hand_domains(), "neutral"); }

/// Paper-preset options for short quiet test runs.
inline stargan::train_options quiet(long iters)
{
    stargan::train_options o;
    o.iters = iters;
    o.threads = 2;
    o.checkpoint_every = 1000;
    o.log_every = 1;
    o.progress_out = nullptr;
    o.seed = 11;
    return o;
}

/// An empty directory under the temporary folder.
inline std::filesystem::path fresh_dir(const char* name)
{
    const std::filesystem::path d = std::filesystem::temp_directory_path() / name;
    std::filesystem::remove_all(d);
    return d;
}

/// A labelled clip of `seconds` at 10 fps (the tempo estimators read durations only).
inline handemo::labelled_clip timed_clip(const std::string& content, const std::string& emotion, double seconds,
                                         const std::string& take = "0")
{
    handemo::labelled_clip c;
    c.path = content + "_" + emotion + "_" + take;
    c.content = content, c.emotion = emotion, c.take = take;
    c.motion = clip::make(hand_skeleton(), static_cast<std::size_t>(std::lround(seconds * 10)), 10);
    return c;
}

/// A labelled clip of `cycles` cycles of a movement of period `period` seconds at 30 fps (a sine on every channel),
/// for the tempo's cadence basis: its duration counts the cycles, its cadence_time() does not.
inline handemo::labelled_clip cycling_clip(const std::string& content, const std::string& emotion, double period, double cycles,
                                           const std::string& take = "0")
{
    handemo::labelled_clip c;
    c.path = content + "_" + emotion + "_" + take;
    c.content = content, c.emotion = emotion, c.take = take;
    const double fps = 30;
    c.motion = clip::make(hand_skeleton(), static_cast<std::size_t>(std::lround(cycles * period * fps)) + 1, fps);
    const std::size_t C = c.motion.skel.size() * 3;
    for (std::size_t f = 0; f < c.motion.frames; ++f)
        for (std::size_t ch = 0; ch < C; ++ch)
            c.motion.angles[f * C + ch] = 20.0 * std::sin(2 * 3.141592653589793 * static_cast<double>(f) / fps / period + 0.4 * static_cast<double>(ch));
    return c;
}

/// The cross-validation error of one tempo estimator in a tempo_fit() result.
inline double cv_error_of(const stargan::tempo_fit_result& r, stargan::tempo_estimator e)
{
    for (const auto& c : r.candidates)
        if (c.estimator == e) return c.cv_error;
    FAIL("no candidate " << stargan::to_string(e));
    return 0;
}

}  // namespace handemo::test
