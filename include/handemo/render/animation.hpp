// Filmstrip animations: clips side by side in one row of filmstrip cells (filmstrip.hpp), playing in sync,
// one picture per output frame. Output frame k is at time t_k = k / fps; clip c shows its frame
// min(n_c - 1, floor(t_k fps_c + 1e-9)) (real time, each clip at its own rate; a clip shorter than the
// longest holds its last frame), or with normalised time min(n_c - 1, round(t_k / T (n_c - 1))) (every
// clip stretched to the longest duration T, so a transferred clip and its input stay aligned). These are
// the viewer page's rules (viewer.hpp), so the GIF and the page show the same frame at the same time.
// The camera and scale are fitted once to every frame of every clip, and every picture is drawn by the
// filmstrip renderer: output frame k is pixel for pixel the one-row filmstrip of the frames it shows.
// No file format here: handemo/gif.hpp (target handemo::gif) writes an animation as an animated GIF.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/image/rgb_image.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/render/filmstrip.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace handemo {

/// @brief Options of filmstrip_animation.
struct animation_options {
    double fps = 0;                 ///< output frames per second; 0: the first clip's rate capped at 30
    bool normalised_time = false;   ///< stretch every clip to the longest clip's duration
    filmstrip_options strip;        ///< cell size, titles, labels, figure (its `rows` is ignored: one row)
};

/// @brief Clips side by side, one picture per output frame (see the file comment for the timing rules).
class filmstrip_animation {
public:
    /// Largest output frame count (a guard against a huge fps or a very long clip): 100 000.
    static constexpr std::size_t max_frames = 100000;

    /// @brief Checks the clips and fits one camera and scale to all their frames.
    /// @throws value_error for no clips, an empty clip (named by its title when there is one), fps not in
    ///         (0, 1000] or more than max_frames output frames; errors of plan_filmstrip.
    filmstrip_animation(std::span<const clip> clips, animation_options opt)
        : clips_(clips.begin(), clips.end()), opt_(std::move(opt))
    {
        const std::string fn = "filmstrip_animation";
        opt_.strip.rows = 1;
        plan_ = plan_filmstrip(clips_, opt_.strip);  // checks clips (none, empty, invalid), titles, sizes
        fps_ = opt_.fps > 0 ? opt_.fps : std::min(clips_.front().fps, 30.0);
        if (!(fps_ > 0) || !(fps_ <= 1000))
            throw value_error(fn + ": fps " + std::to_string(opt_.fps) + " is not in (0, 1000]");
        for (const auto& c : clips_) duration_ = std::max(duration_, c.duration());
        const double n = std::ceil(duration_ * fps_ - 1e-9);
        if (!(n <= static_cast<double>(max_frames)))
            throw value_error(fn + ": " + std::to_string(duration_) + " s at " + std::to_string(fps_) + " fps is more than " +
                              std::to_string(max_frames) + " frames");
        frames_ = std::max<std::size_t>(1, static_cast<std::size_t>(n));
    }

    std::size_t frame_count() const noexcept { return frames_; }
    double fps() const noexcept { return fps_; }
    /// The longest clip's duration in seconds (frames / fps of that clip).
    double duration() const noexcept { return duration_; }
    const animation_options& options() const noexcept { return opt_; }
    /// Time of output frame k in seconds: k / fps.
    double time_of(std::size_t k) const noexcept { return static_cast<double>(k) / fps_; }

    /// @brief The frame of clip `c` shown at time `t` seconds.
    std::size_t clip_frame(std::size_t c, double t) const noexcept
    {
        const clip& cl = clips_[c];
        const double last = static_cast<double>(cl.frames - 1);
        double f = opt_.normalised_time ? std::round(duration_ > 0 ? t / duration_ * last : 0.0) : std::floor(t * cl.fps + 1e-9);
        return static_cast<std::size_t>(std::clamp(f, 0.0, last));
    }

    /// @brief The frame of every clip shown in output frame k.
    std::vector<std::size_t> clip_frames(std::size_t k) const
    {
        std::vector<std::size_t> f;
        for (std::size_t c = 0; c < clips_.size(); ++c) f.push_back(clip_frame(c, time_of(k)));
        return f;
    }

    /// @brief Output frame k: the one-row filmstrip of clip_frames(k).
    /// @throws value_error when k >= frame_count().
    rgb_image frame(std::size_t k) const
    {
        if (k >= frames_)
            throw value_error("filmstrip_animation: frame " + std::to_string(k) + " is not below the frame count " +
                              std::to_string(frames_));
        const double t = time_of(k);
        return detail::draw_filmstrip(clips_, opt_.strip, plan_, 1, [&](std::size_t, std::size_t c) { return clip_frame(c, t); });
    }

private:
    std::vector<clip> clips_;
    animation_options opt_;
    filmstrip_plan plan_;
    double fps_ = 30, duration_ = 0;
    std::size_t frames_ = 1;
};

}  // namespace handemo
