// Recording: reports from a transport -> decoder -> calibration -> pose solve -> a clip at a steady
// frame rate. Each solved pose keeps its timestamp (the device's clock when the profile has one, else
// the host's receive time); take() resamples them linearly onto the output rate. Dropped reports are
// counted (sequence-counter gaps, or timestamp gaps over the nominal period without a counter) and the
// output frames that fall in a gap longer than max_gap_factor report periods are counted as gap_frames:
// they are interpolated across the gap and reported, never silently filled. Malformed reports are
// counted by fault and skipped with a warning; the recording goes on. The BVH is rewritten atomically
// every flush_seconds and on every exit path (end, stop, a disconnect that does not come back), so the
// file on disk is always a valid BVH of everything captured so far. After a reconnect the decoder's clock
// and counter restart and the timeline continues from the host time of the gap. Any protocol's decoder
// (glove_decoder) feeds it; with a glove_reader as the transport, the device is read on its own thread and
// the queue's overruns are counted here too. The accessors copy under a lock, so another thread may read
// them while step() runs.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/glove/profile.hpp>
#include <handemo/glove/solve.hpp>
#include <handemo/glove/transport.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/hand.hpp>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace handemo {

/// @brief Options of a recording.
struct record_options {
    double fps = 60;                        ///< output frame rate of take()
    double seconds = 0;                     ///< stop after this much captured time (0: until stop() or the end of a replay)
    std::filesystem::path out;              ///< BVH rewritten atomically every flush_seconds and at the end (empty: none)
    double flush_seconds = 1;
    std::filesystem::path raw;              ///< copy of every report as a raw stream (empty: none)
    double reconnect_window = 0;            ///< seconds to keep trying to reopen after a disconnect (0: fail at once)
    double reconnect_poll = 0.2;            ///< seconds between reconnect attempts
    std::chrono::milliseconds read_timeout{100};
    double calibration_seconds = 0.5;       ///< IMU glove without a calibration: the first seconds are the flat hand
    double max_gap_factor = 2.5;            ///< an interval longer than this many report periods is a gap
    double keep_seconds = 0;                ///< keep only the newest seconds of poses (live transfer; 0: all)
};

/// @brief Counters of a recording.
struct record_stats {
    std::size_t reports = 0, samples = 0, malformed = 0, dropped = 0, timeouts = 0, reconnects = 0;
    std::size_t warnings = 0;   ///< reports used with a warning (an unknown key)
    std::size_t overruns = 0;   ///< reports lost in a full reader queue (glove_reader)
    std::array<std::size_t, report_fault_count> faults{};  ///< malformed reports and warnings by report_fault
    std::size_t frames = 0, gap_frames = 0;  ///< output frames of the last take() and those inside gaps
    double duration = 0;                     ///< seconds from the first to the last sample
    double rate_hz = 0;                      ///< measured sample rate
    double last_host_time = 0;               ///< host time of the report that completed the newest sample
    double last_arrival = 0;                 ///< when the reader thread received that report (0: no reader thread)
};

/// @brief Records a glove through a transport (see the file comment).
class glove_recorder {
public:
    /// @param calib a calibration, or empty: flex gloves use the profile's nominal values, IMU gloves take
    ///              the first calibration_seconds as the flat hand.
    glove_recorder(glove_transport& t, const glove_profile& p, std::optional<glove_calibration> calib, record_options o)
        : glove_recorder(t, std::make_unique<report_decoder>(p), std::move(calib), std::move(o))
    {
    }
    /// @brief Records with any protocol's decoder; its profile() describes the sensors.
    glove_recorder(glove_transport& t, std::unique_ptr<glove_decoder> decoder, std::optional<glove_calibration> calib, record_options o)
        : t_(t), p_(decoder->profile()), o_(std::move(o)), decoder_(std::move(decoder))
    {
        if (!(o_.fps > 0 && o_.fps <= 10000)) throw value_error("glove record: fps " + std::to_string(o_.fps) + " is not in (0, 10000]");
        if (calib) solver_.emplace(p_, std::move(*calib));
        else if (p_.imus.empty()) solver_.emplace(p_, default_calibration(p_));
        if (!o_.raw.empty()) raw_ = std::make_unique<raw_writer>(o_.raw);
    }

    /// Called with every warning (malformed report, disconnect, reconnect).
    std::function<void(const std::string&)> on_warning;

    /// @brief Reads one report (or times out) and handles it.
    /// @return false when the recording is over: stop(), `seconds` reached, or the replay ended.
    /// @throws device_error after a disconnect that did not come back within the window (the BVH is written first).
    bool step()
    {
        {
            std::lock_guard lock(m_);
            if (stop_.load() || (o_.seconds > 0 && stats_.duration >= o_.seconds) || t_.finished()) return false;
        }
        std::optional<hid_report> r;
        try {
            r = t_.read(o_.read_timeout);
        } catch (const device_error& e) {
            warn(e.what());
            if (o_.reconnect_window > 0) {
                const double start = host_seconds();
                do {
                    if (t_.reconnect()) {
                        std::lock_guard lock(m_);
                        ++stats_.reconnects;
                        if (raw_) raw_->write(hid_report{{}, host_seconds(), 0});  // the reconnect marker
                        decoder_->reset();
                        resync_ = true;
                        warn("reconnected to " + t_.name() + "; the recording goes on");
                        return true;
                    }
                    std::this_thread::sleep_for(std::chrono::duration<double>(o_.reconnect_poll));
                } while (host_seconds() - start < o_.reconnect_window && !stop_.load());
            }
            flush();
            if (o_.reconnect_window > 0)
                throw device_error(std::string(e.what()) + "; no reconnect within " + std::to_string(o_.reconnect_window) + " s");
            throw;
        }
        std::unique_lock lock(m_);
        stats_.overruns = t_.overruns();
        if (!r) {
            ++stats_.timeouts;
            return true;
        }
        ++stats_.reports;
        if (raw_) raw_->write(*r);
        const auto d = decoder_->decode(r->bytes, r->host_time, sample_);
        if (d.fault != report_fault::none) {
            fault(d.fault, d.message);
            return true;
        }
        if (d.warning != report_fault::none) {
            ++stats_.warnings;
            ++stats_.faults[static_cast<std::size_t>(d.warning)];
            warn("report " + std::to_string(stats_.reports) + ": " + d.warning_message);
        }
        if (p_.has_sequence) stats_.dropped += d.dropped;
        if (d.frame) {
            arrival_ = r->arrival;
            if (add(sample_)) {
                lock.unlock();
                flush();
            }
        }
        return true;
    }

    /// @brief Ends the recording at the next step (safe from a signal handler).
    void stop() noexcept { stop_.store(true); }
    /// @brief Runs step() until it returns false, then flushes.
    void run()
    {
        while (step()) {
        }
        flush();
    }

    bool calibrated() const
    {
        std::lock_guard lock(m_);
        return solver_.has_value();
    }
    /// The calibration in use (empty while an IMU glove is still collecting its flat-hand seconds).
    std::optional<glove_calibration> calibration() const
    {
        std::lock_guard lock(m_);
        return solver_ ? std::optional<glove_calibration>(solver_->calibration()) : std::nullopt;
    }
    const glove_profile& profile() const noexcept { return p_; }
    /// The decoder (protocol state such as opengloves_decoder::state()); use it from the recording thread.
    const glove_decoder& decoder() const noexcept { return *decoder_; }
    record_stats stats() const
    {
        std::lock_guard lock(m_);
        return stats_;
    }
    /// Timestamps (seconds from the first sample) of the solved poses, a copy.
    std::vector<double> times() const
    {
        std::lock_guard lock(m_);
        return times_;
    }
    /// Solved poses, [samples, 23, 3] degrees, a copy.
    std::vector<double> poses() const
    {
        std::lock_guard lock(m_);
        return poses_;
    }
    /// Number of solved poses and the seconds they span.
    std::pair<std::size_t, double> extent() const
    {
        std::lock_guard lock(m_);
        return {times_.size(), times_.empty() ? 0.0 : times_.back() - times_.front()};
    }

    /// @brief The recording at the output frame rate (the newest `last_seconds` of it when > 0).
    /// Updates stats().frames and stats().gap_frames.
    clip take(double last_seconds = 0)
    {
        std::lock_guard lock(m_);
        constexpr std::size_t J3 = hand_joint_count * 3;
        const std::size_t n = times_.size();
        if (n == 0) return clip::make(hand_skeleton(), 0, o_.fps);
        const double t_end = times_.back();
        double t0 = times_.front();
        if (last_seconds > 0 && t_end - last_seconds > t0) t0 = t_end - last_seconds;
        const auto frames = static_cast<std::size_t>(std::floor((t_end - t0) * o_.fps + 1e-9)) + 1;
        clip c = clip::make(hand_skeleton(), frames, o_.fps);
        const double gap = o_.max_gap_factor / p_.rate_hz;
        std::size_t k = 0, gaps = 0;
        for (std::size_t f = 0; f < frames; ++f) {
            const double t = t0 + static_cast<double>(f) / o_.fps;
            while (k + 1 < n && times_[k + 1] <= t) ++k;
            double* dst = c.angles.data() + f * J3;
            const double* a = poses_.data() + k * J3;
            if (k + 1 >= n || times_[k] >= t) {
                std::copy(a, a + J3, dst);
                continue;
            }
            const double* b = a + J3;
            const double dt = times_[k + 1] - times_[k], w = (t - times_[k]) / dt;
            if (dt > gap) ++gaps;
            for (std::size_t i = 0; i < J3; ++i) dst[i] = (1 - w) * a[i] + w * b[i];
        }
        stats_.frames = frames;
        stats_.gap_frames = gaps;
        return c;
    }

    /// @brief Writes the BVH (when `out` is set and something was captured), atomically.
    void flush()
    {
        clip c;
        {
            std::lock_guard lock(m_);
            if (raw_) raw_->flush();
            if (o_.out.empty() || times_.empty()) return;
            c = take();
            last_flush_ = times_.back();
        }
        write_bvh(o_.out, c);
    }

private:
    void warn(const std::string& m)
    {
        if (on_warning) on_warning(m);
    }
    void fault(report_fault f, const std::string& m)
    {
        ++stats_.malformed;
        ++stats_.faults[static_cast<std::size_t>(f)];
        warn("report " + std::to_string(stats_.reports) + " skipped: " + m);
    }
    /// Adds a sample; true when the BVH is due to be rewritten.
    bool add(const glove_sample& s)
    {
        constexpr std::size_t J3 = hand_joint_count * 3;
        if (resync_ || !started_) {
            // The first sample, or the first after a reconnect: the device clock may have restarted.
            const double continue_at = started_ ? last_time_ + std::max(1.0 / p_.rate_hz, s.host_time - stats_.last_host_time) : 0.0;
            offset_ = continue_at - s.time();
            resync_ = false;
        }
        const double t = s.time() + offset_;
        if (started_ && !(t > last_time_)) {
            fault(report_fault::clock_backwards, "sample time " + std::to_string(t) + " s does not advance past " + std::to_string(last_time_) + " s");
            return false;
        }
        if (started_ && !p_.has_sequence) {
            const double missing = std::round((t - last_time_) * p_.rate_hz) - 1;
            if (missing >= 1) stats_.dropped += static_cast<std::size_t>(missing);
        }
        if (!started_) first_time_ = t;
        started_ = true;
        last_time_ = t;
        stats_.last_host_time = s.host_time;
        stats_.last_arrival = arrival_;
        ++stats_.samples;
        stats_.duration = t - first_time_;
        stats_.rate_hz = stats_.duration > 0 ? static_cast<double>(stats_.samples - 1) / stats_.duration : 0;
        if (!solver_) {
            pending_.push_back(s);
            pending_times_.push_back(t);
            if (t - first_time_ < o_.calibration_seconds) return false;
            solver_.emplace(p_, calibrate_glove(p_, pending_));
            for (std::size_t i = 0; i < pending_.size(); ++i) push_pose(pending_[i], pending_times_[i]);
            pending_.clear(), pending_times_.clear();
        } else {
            push_pose(s, t);
        }
        if (o_.keep_seconds > 0 && times_.size() > 1 && times_.back() - times_.front() > 2 * o_.keep_seconds) {
            std::size_t cut = 0;
            while (cut + 1 < times_.size() && times_.back() - times_[cut + 1] >= o_.keep_seconds) ++cut;
            times_.erase(times_.begin(), times_.begin() + static_cast<std::ptrdiff_t>(cut));
            poses_.erase(poses_.begin(), poses_.begin() + static_cast<std::ptrdiff_t>(cut * J3));
        }
        return !o_.out.empty() && !times_.empty() && times_.back() - last_flush_ >= o_.flush_seconds;
    }
    void push_pose(const glove_sample& s, double t)
    {
        constexpr std::size_t J3 = hand_joint_count * 3;
        const std::size_t at = poses_.size();
        poses_.resize(at + J3);
        solver_->solve(s, poses_.data() + at);
        times_.push_back(t - first_time_);
    }

    glove_transport& t_;
    glove_profile p_;
    record_options o_;
    std::unique_ptr<glove_decoder> decoder_;
    std::optional<hand_solver> solver_;
    std::unique_ptr<raw_writer> raw_;
    glove_sample sample_;
    std::vector<glove_sample> pending_;
    std::vector<double> pending_times_, times_, poses_;
    record_stats stats_;
    std::atomic<bool> stop_{false};
    bool started_ = false, resync_ = false;
    double offset_ = 0, first_time_ = 0, last_time_ = 0, last_flush_ = 0, arrival_ = 0;
    mutable std::recursive_mutex m_;
};

}  // namespace handemo
