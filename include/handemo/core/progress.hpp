// Progress reporting for long work (training, evaluation): a one-line bar with rate, ETA and a status
// text on a terminal, and plain periodic lines when the output is a file or a pipe (CI logs).
#pragma once

#include <chrono>
#include <cstdio>
#include <string>
#include <string_view>
#include <unistd.h>

namespace handemo {

/// @brief Formats seconds as `1h02m`, `3m05s` or `42s`.
inline std::string format_duration(double seconds)
{
    if (!(seconds >= 0) || seconds > 1e7) return "--";
    const long s = static_cast<long>(seconds + 0.5);
    char buf[32];
    if (s >= 3600)
        std::snprintf(buf, sizeof buf, "%ldh%02ldm", s / 3600, (s / 60) % 60);
    else if (s >= 60)
        std::snprintf(buf, sizeof buf, "%ldm%02lds", s / 60, s % 60);
    else
        std::snprintf(buf, sizeof buf, "%lds", s);
    return buf;
}

/// @brief A progress bar over `total` steps with an ETA from the mean rate so far.
/// On a terminal it redraws one line (at most 10 times a second); otherwise it prints a line every
/// `plain_every_seconds` and at the end, so logs stay short.
class progress {
public:
    progress(std::string label, long total, std::FILE* out = stderr, double plain_every_seconds = 10.0)
        : label_(std::move(label)), total_(total > 0 ? total : 1), out_(out),
          tty_(out != nullptr && ::isatty(::fileno(out)) != 0), plain_every_(plain_every_seconds),
          start_(clock::now()), last_(start_ - std::chrono::hours(1))
    {
    }
    progress(const progress&) = delete;
    progress& operator=(const progress&) = delete;
    ~progress() { finish(); }

    /// Seconds since the start.
    double elapsed() const { return std::chrono::duration<double>(clock::now() - start_).count(); }
    /// Estimated seconds left after `done` steps.
    double eta(long done) const
    {
        if (done <= 0) return -1;
        return elapsed() / static_cast<double>(done) * static_cast<double>(total_ - done);
    }

    /// @brief Reports that `done` of `total` steps are finished, with a short status (e.g. losses).
    void update(long done, std::string_view status = {})
    {
        done_ = done;
        if (!out_) return;
        const auto now = clock::now();
        const double since = std::chrono::duration<double>(now - last_).count();
        const bool last_step = done >= total_;
        if (tty_ ? (since < 0.1 && !last_step) : (since < plain_every_ && !last_step)) return;
        last_ = now;
        const double frac = static_cast<double>(done) / static_cast<double>(total_);
        if (tty_) {
            constexpr int width = 24;
            const int filled = static_cast<int>(frac * width);
            std::string bar(static_cast<std::size_t>(filled), '#');
            bar.resize(width, '.');
            std::fprintf(out_, "\r\033[K%s [%s] %ld/%ld %3.0f%% %s elapsed, ETA %s %.*s", label_.c_str(), bar.c_str(),
                         done, total_, 100 * frac, format_duration(elapsed()).c_str(), format_duration(eta(done)).c_str(),
                         static_cast<int>(status.size()), status.data());
            if (last_step) std::fputc('\n', out_), drawn_final_ = true;
        } else {
            std::fprintf(out_, "%s %ld/%ld (%.0f%%) elapsed %s ETA %s %.*s\n", label_.c_str(), done, total_, 100 * frac,
                         format_duration(elapsed()).c_str(), format_duration(eta(done)).c_str(),
                         static_cast<int>(status.size()), status.data());
            drawn_final_ = last_step;
        }
        std::fflush(out_);
    }
    /// Ends the line on a terminal.
    void finish()
    {
        if (out_ && tty_ && !drawn_final_ && done_ > 0) {
            std::fputc('\n', out_);
            drawn_final_ = true;
        }
    }

private:
    using clock = std::chrono::steady_clock;
    std::string label_;
    long total_;
    std::FILE* out_;
    bool tty_;
    double plain_every_;
    clock::time_point start_, last_;
    long done_ = 0;
    bool drawn_final_ = false;
};

}  // namespace handemo
