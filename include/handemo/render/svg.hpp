// SVG plots written as plain text (no library). The StarGAN training losses of the hand paper (Eq. 4 and
// Eq. 5: L_D = -L_adv + lambda_cls L_cls^r, L_G = L_adv + lambda_cls L_cls^f + lambda_rec L_rec) from a CSV
// log as small multiples: one panel per group of terms (D terms, G terms, D accuracy, learning rate) on a
// shared step axis, linear y axes, each series in its own colour as an exponential moving average over its
// raw values drawn faint. Per-fold evaluation numbers as small multiples too (one panel per metric, one line
// per method), and grouped bar charts with error bars (mean +- std per metric and method) for evaluation
// summaries. choose_y_scale / axis_scale remain for callers that want a log or symmetric-log axis. All text
// is XML-escaped.
#pragma once

#include <handemo/core/error.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

/// How values map to the vertical axis.
enum class axis_scale { linear, log, symlog };

/// @brief Options of plot_losses_svg.
struct loss_plot_options {
    std::size_t width = 860;
    std::size_t panel_height = 200;  ///< pixels per panel (one panel per group of terms)
    std::string title = "training losses";
    std::size_t max_points = 2000;  ///< longer series are averaged in equal buckets of steps
    double ema_alpha = 0;           ///< weight of the newest value in the moving average; 0 = automatic (loss_ema_alpha)
};

/// @brief One bar of an evaluation summary: `mean` +- `std` of `metric` for `method`.
struct bar_entry {
    std::string metric, method;
    double mean = 0, std = 0;
};

/// @brief Options of plot_bars_svg.
struct bar_plot_options {
    std::size_t panel_width = 260, panel_height = 260;
    std::size_t panels_per_row = 4;
    std::string title = "evaluation";
};

namespace detail {

/// Escapes the five XML special characters; drops other control characters, which XML 1.0 forbids.
inline std::string xml_escape(std::string_view s)
{
    std::string r;
    r.reserve(s.size());
    for (char ch : s) {
        switch (ch) {
        case '&': r += "&amp;"; break;
        case '<': r += "&lt;"; break;
        case '>': r += "&gt;"; break;
        case '"': r += "&quot;"; break;
        case '\'': r += "&apos;"; break;
        default:
            if (static_cast<unsigned char>(ch) >= 0x20 || ch == '\t' || ch == '\n') r += ch;
        }
    }
    return r;
}

/// A number with up to `digits` significant digits, no trailing zeros ("0.001", "2.5e+06").
inline std::string fmt_num(double v, int digits = 4)
{
    if (v == 0) return "0";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", digits, v);
    return buf;
}

/// Coordinates with two decimals (plenty for an SVG user unit).
inline std::string fmt_px(double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2f", v);
    std::string s = buf;
    while (s.size() > 1 && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
    return s == "-0" ? "0" : s;
}

inline std::string_view trim(std::string_view s) noexcept
{
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return s;
}

inline std::vector<std::string_view> split_csv_line(std::string_view line)
{
    std::vector<std::string_view> f;
    std::size_t start = 0;
    for (std::size_t i = 0; i <= line.size(); ++i)
        if (i == line.size() || line[i] == ',') {
            f.push_back(trim(line.substr(start, i - start)));
            start = i + 1;
        }
    return f;
}

/// Lines of `text` with their 1-based numbers, without '\r', skipping blank lines and '#' comments.
inline std::vector<std::pair<long, std::string_view>> csv_lines(std::string_view text)
{
    std::vector<std::pair<long, std::string_view>> out;
    long no = 0;
    while (!text.empty() || no == 0) {
        ++no;
        const std::size_t nl = text.find('\n');
        std::string_view line = text.substr(0, nl);
        text = nl == std::string_view::npos ? std::string_view{} : text.substr(nl + 1);
        if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
        if (!trim(line).empty() && trim(line).front() != '#') out.emplace_back(no, line);
        if (text.empty()) break;
    }
    return out;
}

/// Parses a number; empty, "nan" or "-" mean missing (returns NaN).
inline double parse_cell(std::string_view cell, const std::string& what, long line, std::string_view column)
{
    if (cell.empty() || cell == "-" || cell == "nan" || cell == "NaN") return std::nan("");
    double v = 0;
    const char* b = cell.data();
    if (*b == '+') ++b;
    const auto [ptr, ec] = std::from_chars(b, cell.data() + cell.size(), v);
    if (ec != std::errc{} || ptr != cell.data() + cell.size())
        throw format_error(what + ": line " + std::to_string(line) + ": column '" + std::string(column) + "' value '" +
                           std::string(cell) + "' is not a number");
    return v;
}

/// Tick positions 1, 2 or 5 x 10^k apart covering [lo, hi] with about `n` ticks.
inline std::vector<double> nice_ticks(double lo, double hi, int n = 6)
{
    if (!(hi > lo)) return {lo};
    const double raw = (hi - lo) / std::max(n, 1), mag = std::pow(10.0, std::floor(std::log10(raw)));
    double step = mag;
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * mag >= raw) {
            step = m * mag;
            break;
        }
    std::vector<double> t;
    for (double v = std::ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step) t.push_back(std::abs(v) < step * 1e-9 ? 0.0 : v);
    return t;
}

/// A vertical axis: value -> pixel for one of the three scales.
struct y_axis {
    axis_scale kind = axis_scale::linear;
    double lo = 0, hi = 1;  ///< in transformed units
    double c = 1;           ///< symlog linear threshold
    double top = 0, bottom = 1;

    double transform(double v) const noexcept
    {
        switch (kind) {
        case axis_scale::log: return std::log10(v);
        case axis_scale::symlog: return (v < 0 ? -1.0 : 1.0) * std::log10(1.0 + std::abs(v) / c);
        default: return v;
        }
    }
    double pixel(double v) const noexcept { return bottom - (transform(v) - lo) / (hi - lo) * (bottom - top); }
};

inline constexpr std::array<std::string_view, 10> plot_palette{"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                                                                "#17becf", "#e377c2", "#8c564b", "#7f7f7f", "#bcbd22"};

/// Builds the y axis over `values` (finite entries only) for the chosen scale, with tick values.
inline y_axis make_y_axis(axis_scale kind, std::span<const double> values, double top, double bottom, std::vector<double>& ticks)
{
    y_axis ax;
    ax.kind = kind;
    ax.top = top;
    ax.bottom = bottom;
    double lo = 1e300, hi = -1e300, amin = 1e300;
    for (double v : values) {
        if (!std::isfinite(v)) continue;
        lo = std::min(lo, v), hi = std::max(hi, v);
        if (v != 0) amin = std::min(amin, std::abs(v));
    }
    if (!(hi >= lo)) lo = 0, hi = 1;
    ticks.clear();
    if (kind == axis_scale::log) {
        const double a = std::floor(std::log10(lo)), b = std::ceil(std::log10(hi));
        ax.lo = a, ax.hi = std::max(b, a + 1);
        for (double e = ax.lo; e <= ax.hi + 1e-9; e += 1) ticks.push_back(std::pow(10.0, e));
    } else if (kind == axis_scale::symlog) {
        ax.c = std::pow(10.0, std::floor(std::log10(amin < 1e300 ? amin : 1.0)));
        ax.lo = ax.transform(lo), ax.hi = ax.transform(hi);
        if (ax.lo > 0) ax.lo = 0;
        if (ax.hi < 0) ax.hi = 0;
        ticks.push_back(0);
        const double amax = std::max(std::abs(lo), std::abs(hi));
        for (double m = ax.c; m <= amax * 1.0001; m *= 10) {
            if (m <= hi) ticks.push_back(m);
            if (-m >= lo) ticks.push_back(-m);
        }
        std::sort(ticks.begin(), ticks.end());
    } else {
        if (hi - lo < 1e-12 * std::max(1.0, std::abs(hi))) lo -= 0.5, hi += 0.5;
        ticks = nice_ticks(lo, hi);
        const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0;
        ax.lo = std::min(lo, ticks.front());
        ax.hi = std::max(hi, ticks.back());
        if (ticks.front() > lo) ax.lo = ticks.front() - step;
        if (ticks.back() < hi) ax.hi = ticks.back() + step;
    }
    if (!(ax.hi > ax.lo)) ax.hi = ax.lo + 1;
    return ax;
}

inline void svg_text(std::string& out, double x, double y, std::string_view text, std::string_view anchor = "start",
                     int size = 12, std::string_view extra = {})
{
    out += "<text x=\"" + fmt_px(x) + "\" y=\"" + fmt_px(y) + "\" font-size=\"" + std::to_string(size) + "\" text-anchor=\"" +
           std::string(anchor) + "\"" + (extra.empty() ? "" : " " + std::string(extra)) + ">" + xml_escape(text) + "</text>\n";
}

inline void svg_line(std::string& out, double x0, double y0, double x1, double y1, std::string_view stroke, double w = 1)
{
    out += "<line x1=\"" + fmt_px(x0) + "\" y1=\"" + fmt_px(y0) + "\" x2=\"" + fmt_px(x1) + "\" y2=\"" + fmt_px(y1) +
           "\" stroke=\"" + std::string(stroke) + "\" stroke-width=\"" + fmt_px(w) + "\"/>\n";
}

inline std::string svg_open(std::size_t w, std::size_t h)
{
    return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(w) +
           "\" height=\"" + std::to_string(h) + "\" viewBox=\"0 0 " + std::to_string(w) + " " + std::to_string(h) +
           "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">\n<rect x=\"0\" y=\"0\" width=\"" + std::to_string(w) +
           "\" height=\"" + std::to_string(h) + "\" fill=\"white\"/>\n";
}

/// The frame of a small-multiples plot: panel grid, SVG header, title and a legend of `series` on top (a dot on each
/// legend line when `dots`); origin(k) is the top-left corner of panel k.
struct multiples_frame {
    std::size_t per_row = 1;
    double pw = 0, ph = 0, top = 0, W = 0, H = 0;
    std::pair<double, double> origin(std::size_t k) const noexcept
    {
        return {10 + pw * static_cast<double>(k % per_row), top + ph * static_cast<double>(k / per_row)};
    }
};
/// Appends `s` to `v` unless it is there already (first-appearance order of panels, series and folds).
inline void add_unique(std::vector<std::string>& v, const std::string& s)
{
    if (std::find(v.begin(), v.end(), s) == v.end()) v.push_back(s);
}

/// Horizontal grid lines with their value labels for the ticks of `ay` inside [T, B] (the zero line in `zero_stroke`).
inline void y_grid(std::string& out, const y_axis& ay, const std::vector<double>& ticks, double L, double R, double T, double B,
                   std::string_view zero_stroke)
{
    for (double t : ticks) {
        const double y = ay.pixel(t);
        if (y < T - 0.5 || y > B + 0.5) continue;
        svg_line(out, L, y, R, y, t == 0 ? zero_stroke : "#ececec");
        svg_text(out, L - 6, y + 4, fmt_num(t), "end", 10);
    }
}

inline multiples_frame open_multiples(std::string& out, std::size_t panels, const std::vector<std::string>& series, std::size_t per_row,
                                      double pw, double ph, const std::string& title, bool dots)
{
    multiples_frame f;
    f.per_row = std::max<std::size_t>(1, std::min(per_row, panels));
    const std::size_t rows = (panels + f.per_row - 1) / f.per_row;
    f.pw = pw, f.ph = ph;
    f.top = 40 + 20.0 * static_cast<double>((series.size() + 3) / 4) + 8;
    f.W = pw * static_cast<double>(f.per_row) + 20, f.H = f.top + ph * static_cast<double>(rows) + 10;
    out = svg_open(static_cast<std::size_t>(f.W), static_cast<std::size_t>(f.H));
    svg_text(out, f.W / 2, 24, title, "middle", 16, "font-weight=\"bold\"");
    for (std::size_t m = 0; m < series.size(); ++m) {
        const double lx = 20 + static_cast<double>(m % 4) * (f.W - 40) / 4, ly = 44 + 20.0 * static_cast<double>(m / 4);
        const std::string_view c = plot_palette[m % plot_palette.size()];
        svg_line(out, lx, ly - 3, lx + 22, ly - 3, c, 2.5);
        if (dots) out += "<circle cx=\"" + fmt_px(lx + 11) + "\" cy=\"" + fmt_px(ly - 3) + "\" r=\"3\" fill=\"" + std::string(c) + "\"/>\n";
        svg_text(out, lx + 28, ly + 1, series[m], "start", 12, "class=\"legend\"");
    }
    return f;
}

}  // namespace detail

/// @brief The y-axis scale for a set of values (non-finite values are ignored).
/// @return log when all values are positive and max / min > 10 (more than one decade); symlog when
///         values of both signs occur and max|v| / min nonzero |v| > 1000; linear otherwise.
inline axis_scale choose_y_scale(std::span<const double> values) noexcept
{
    double lo = 1e300, hi = -1e300, amin = 1e300, amax = 0;
    for (double v : values) {
        if (!std::isfinite(v)) continue;
        lo = std::min(lo, v), hi = std::max(hi, v);
        if (v != 0) amin = std::min(amin, std::abs(v)), amax = std::max(amax, std::abs(v));
    }
    if (!(hi >= lo)) return axis_scale::linear;
    if (lo > 0 && hi / lo > 10.0) return axis_scale::log;
    if (lo < 0 && hi > 0 && amax / amin > 1000.0) return axis_scale::symlog;
    return axis_scale::linear;
}

/// @brief A training-loss log: `step` and one named series per loss term (NaN where a cell is empty).
struct loss_log {
    std::vector<std::string> terms;           ///< [T] column names after `step`
    std::vector<double> steps;                ///< [N]
    std::vector<std::vector<double>> values;  ///< [T][N]
};

/// @brief Parses a CSV loss log: header `step,<term>,...`, then numeric rows ('#' lines and blank lines
/// are skipped; an empty cell, `nan` or `-` is a missing value).
/// @throws format_error naming `what`, the line and the column for a missing header, a first column
///         other than `step`, a row with the wrong number of fields, or a cell that is not a number.
inline loss_log parse_loss_csv(std::string_view text, const std::string& what = "loss log")
{
    const auto lines = detail::csv_lines(text);
    if (lines.empty()) throw format_error(what + ": empty file, expected a header 'step,<loss>,...'");
    const auto header = detail::split_csv_line(lines[0].second);
    std::string first(header[0]);
    for (auto& ch : first) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (first != "step")
        throw format_error(what + ": line " + std::to_string(lines[0].first) + ": first column '" + std::string(header[0]) +
                           "' is not 'step'");
    if (header.size() < 2)
        throw format_error(what + ": line " + std::to_string(lines[0].first) + ": header has no loss column after 'step'");
    loss_log log;
    for (std::size_t i = 1; i < header.size(); ++i) {
        if (header[i].empty())
            throw format_error(what + ": line " + std::to_string(lines[0].first) + ": column " + std::to_string(i + 1) + " has no name");
        log.terms.emplace_back(header[i]);
    }
    log.values.resize(log.terms.size());
    for (std::size_t r = 1; r < lines.size(); ++r) {
        const auto [no, line] = lines[r];
        const auto f = detail::split_csv_line(line);
        if (f.size() != header.size())
            throw format_error(what + ": line " + std::to_string(no) + ": " + std::to_string(f.size()) + " fields, expected " +
                               std::to_string(header.size()) + " (as in the header)");
        const double step = detail::parse_cell(f[0], what, no, header[0]);
        if (!std::isfinite(step)) throw format_error(what + ": line " + std::to_string(no) + ": column 'step' is empty or not finite");
        log.steps.push_back(step);
        for (std::size_t t = 0; t < log.terms.size(); ++t) log.values[t].push_back(detail::parse_cell(f[t + 1], what, no, header[t + 1]));
    }
    if (log.steps.empty()) throw format_error(what + ": no data rows after the header");
    return log;
}

/// @brief The group (panel) a loss-log column belongs to: "D terms" (names starting `D/`, `d_`, `D.`),
/// "G terms" (`G/`, `g_`, `G.`), "D accuracy" (any name containing `acc`), "learning rate" (`lr`, or a name
/// containing `learning`), else "other terms". Panels appear in this order.
inline std::string loss_group_of(std::string_view term)
{
    std::string n(term);
    for (auto& ch : n) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (n == "lr" || n.starts_with("lr_") || n.starts_with("lr/") || n.find("learning") != std::string::npos) return "learning rate";
    if (n.find("acc") != std::string::npos) return "D accuracy";
    auto pre = [&](char c) { return n.size() > 1 && n[0] == c && (n[1] == '/' || n[1] == '_' || n[1] == '.'); };
    if (pre('d')) return "D terms";
    if (pre('g')) return "G terms";
    return "other terms";
}

/// @brief The smoothing weight used for a log of `rows` rows: `requested` when it is in (0, 1], else
/// automatic, 2 / (span + 1) with span = max(1, rows / 25) (a window of about 4% of the run).
inline double loss_ema_alpha(std::size_t rows, double requested = 0) noexcept
{
    if (requested > 0 && requested <= 1) return requested;
    const double span = std::max(1.0, std::floor(static_cast<double>(rows) / 25.0));
    return 2.0 / (span + 1.0);
}

/// @brief Exponential moving average: e_0 = x_0, e_i = alpha x_i + (1 - alpha) e_(i-1). Non-finite
/// entries give NaN and leave the average unchanged (the next finite value continues from it).
inline std::vector<double> exponential_moving_average(std::span<const double> x, double alpha)
{
    std::vector<double> e(x.size(), std::nan(""));
    bool started = false;
    double acc = 0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        if (!std::isfinite(x[i])) continue;
        acc = started ? alpha * x[i] + (1 - alpha) * acc : x[i];
        started = true;
        e[i] = acc;
    }
    return e;
}

/// @brief Plots a CSV training log as small multiples: one panel per group of terms (loss_group_of: D
/// terms, G terms, D accuracy, learning rate), all sharing one step axis, each with its own linear y axis.
/// Every series is drawn twice in its own colour: the raw values faint, and their exponential moving
/// average (the weight is written under the title) as the line. A series with no finite nonzero value
/// (a column an old log fills with 0 or NaN) is left out and named in a note. The y range of a panel covers
/// the averages and the 1st-99th percentile of the raw values (raw spikes beyond it are clipped, which the
/// subtitle says). Each panel's frame carries `data-lo`/`data-hi` (values at its bottom/top edge) and
/// `data-x0`/`data-x1` (steps at its left/right edge); each average line has `class="ema"` and
/// `data-series`, each raw line `class="raw"`, each legend label `class="legend"`.
/// @param csv_text header `step,<term>,...` then numeric rows (see parse_loss_csv).
/// @return the SVG document.
/// @throws format_error from parse_loss_csv.
inline std::string plot_losses_svg(std::string_view csv_text, const loss_plot_options& opt = {})
{
    const loss_log log = parse_loss_csv(csv_text, "plot_losses_svg");
    const std::size_t n = log.steps.size();
    const double alpha = loss_ema_alpha(n, opt.ema_alpha);

    // Groups in panel order, with the non-empty series of each.
    const std::array<std::string_view, 5> order{"D terms", "G terms", "D accuracy", "learning rate", "other terms"};
    std::vector<std::string> groups;
    std::vector<std::vector<std::size_t>> members;
    std::vector<std::string> skipped;
    for (auto g : order) {
        std::vector<std::size_t> m;
        for (std::size_t t = 0; t < log.terms.size(); ++t) {
            if (loss_group_of(log.terms[t]) != g) continue;
            const bool empty = std::none_of(log.values[t].begin(), log.values[t].end(), [](double v) { return std::isfinite(v) && v != 0; });
            if (empty)
                skipped.push_back(log.terms[t]);
            else
                m.push_back(t);
        }
        if (!m.empty()) groups.emplace_back(g), members.push_back(std::move(m));
    }

    const double W = static_cast<double>(std::max<std::size_t>(opt.width, 420));
    const double ph = static_cast<double>(std::max<std::size_t>(opt.panel_height, 120));
    const double head = 58, L = 72, R = W - 170;
    const double H = head + ph * static_cast<double>(std::max<std::size_t>(groups.size(), 1)) + 34 + (skipped.empty() ? 0 : 16);
    double s0 = *std::min_element(log.steps.begin(), log.steps.end()), s1 = *std::max_element(log.steps.begin(), log.steps.end());
    if (!(s1 > s0)) s0 -= 0.5, s1 += 0.5;
    auto px = [&](double s) { return L + (s - s0) / (s1 - s0) * (R - L); };
    const std::vector<double> xt = detail::nice_ticks(s0, s1, 8);

    std::string out = detail::svg_open(static_cast<std::size_t>(W), static_cast<std::size_t>(H));
    detail::svg_text(out, W / 2, 22, opt.title, "middle", 16, "font-weight=\"bold\"");
    bool clipped_any = false;
    std::string body;
    for (std::size_t g = 0; g < groups.size(); ++g) {
        const double oy = head + ph * static_cast<double>(g), T = oy + 22, B = oy + ph - 24;
        // y range: every average, and the 1st..99th percentile of the raw values
        std::vector<std::vector<double>> emas;
        std::vector<double> raw, range;
        for (auto t : members[g]) {
            emas.push_back(exponential_moving_average(log.values[t], alpha));
            for (double v : emas.back())
                if (std::isfinite(v)) range.push_back(v);
            for (double v : log.values[t])
                if (std::isfinite(v)) raw.push_back(v);
        }
        std::sort(raw.begin(), raw.end());
        const auto q = [&](double p) { return raw[static_cast<std::size_t>(std::llround(p * static_cast<double>(raw.size() - 1)))]; };
        const double qlo = raw.size() >= 50 ? q(0.01) : raw.front(), qhi = raw.size() >= 50 ? q(0.99) : raw.back();
        range.push_back(qlo);
        range.push_back(qhi);
        if (raw.front() < *std::min_element(range.begin(), range.end()) || raw.back() > *std::max_element(range.begin(), range.end()))
            clipped_any = true;
        std::vector<double> yt;
        const detail::y_axis ay = detail::make_y_axis(axis_scale::linear, range, T, B, yt);
        const std::string clip_id = "panel" + std::to_string(g);
        body += "<clipPath id=\"" + clip_id + "\"><rect x=\"" + detail::fmt_px(L) + "\" y=\"" + detail::fmt_px(T) + "\" width=\"" +
                detail::fmt_px(R - L) + "\" height=\"" + detail::fmt_px(B - T) + "\"/></clipPath>\n";
        detail::svg_text(body, L, oy + 15, groups[g], "start", 13, "font-weight=\"bold\"");
        for (double t : yt) {
            const double y = ay.pixel(t);
            if (y < T - 0.5 || y > B + 0.5) continue;
            detail::svg_line(body, L, y, R, y, t == 0 ? "#b0b0b0" : "#ececec");
            detail::svg_line(body, L - 4, y, L, y, "#444");
            detail::svg_text(body, L - 7, y + 4, detail::fmt_num(t), "end", 10);
        }
        for (double t : xt) {
            const double x = px(t);
            detail::svg_line(body, x, B, x, B + 4, "#444");
            detail::svg_text(body, x, B + 15, detail::fmt_num(t, 6), "middle", 10);
        }
        body += "<g clip-path=\"url(#" + clip_id + ")\">\n";
        const std::size_t maxp = std::max<std::size_t>(opt.max_points, 2), per = (n + maxp - 1) / maxp;
        for (std::size_t k = 0; k < members[g].size(); ++k) {
            const std::size_t t = members[g][k];
            const std::string colour(detail::plot_palette[k % detail::plot_palette.size()]);
            std::string rp, ep;
            // raw: averaged in buckets of `per` rows when longer than max_points; average: its value at
            // the bucket's last finite row
            for (std::size_t i = 0; i < n; i += per) {
                double sx = 0, sy = 0, m = 0, ex = std::nan(""), ey = std::nan("");
                for (std::size_t r = i; r < std::min(n, i + per); ++r) {
                    if (!std::isfinite(log.values[t][r])) continue;
                    sx += log.steps[r], sy += log.values[t][r], m += 1;
                    ex = log.steps[r], ey = emas[k][r];
                }
                if (m == 0) continue;
                rp += (rp.empty() ? "" : " ") + detail::fmt_px(px(sx / m)) + "," + detail::fmt_px(ay.pixel(sy / m));
                ep += (ep.empty() ? "" : " ") + detail::fmt_px(px(ex)) + "," + detail::fmt_px(ay.pixel(ey));
            }
            const std::string name = detail::xml_escape(log.terms[t]);
            body += "<polyline class=\"raw\" fill=\"none\" stroke=\"" + colour + "\" stroke-opacity=\"0.28\" stroke-width=\"1\" points=\"" +
                    rp + "\"/>\n";
            body += "<polyline class=\"ema\" data-series=\"" + name + "\" fill=\"none\" stroke=\"" + colour +
                    "\" stroke-width=\"1.8\" stroke-linejoin=\"round\" points=\"" + ep + "\"><title>" + name +
                    " (moving average)</title></polyline>\n";
            const double ly = T + 8 + 18.0 * static_cast<double>(k);
            detail::svg_line(body, R + 14, ly, R + 36, ly, colour, 2.5);
            detail::svg_text(body, R + 42, ly + 4, log.terms[t], "start", 11, "class=\"legend\"");
        }
        body += "</g>\n";
        body += "<rect class=\"panel\" data-group=\"" + detail::xml_escape(groups[g]) + "\" data-lo=\"" + detail::fmt_num(ay.lo, 15) +
                "\" data-hi=\"" + detail::fmt_num(ay.hi, 15) + "\" data-x0=\"" + detail::fmt_num(s0, 15) + "\" data-x1=\"" +
                detail::fmt_num(s1, 15) + "\" x=\"" + detail::fmt_px(L) + "\" y=\"" + detail::fmt_px(T) + "\" width=\"" +
                detail::fmt_px(R - L) + "\" height=\"" + detail::fmt_px(B - T) + "\" fill=\"none\" stroke=\"#444\"/>\n";
    }
    char a[32];
    std::snprintf(a, sizeof a, "%.3g", alpha);
    std::string sub = std::string("lines: exponential moving average e = ") + a + " x + " + detail::fmt_num(1 - alpha, 3) +
                      " e(previous row); faint: raw values";
    if (clipped_any) sub += "; y axes cover the 1st-99th percentile";
    detail::svg_text(out, W / 2, 40, sub, "middle", 11, "fill=\"#555\"");
    out += body;
    detail::svg_text(out, (L + R) / 2, H - 14 - (skipped.empty() ? 0 : 16), "step", "middle", 12);
    if (!skipped.empty()) {
        std::string s = "not plotted (every value 0 or missing): ";
        for (std::size_t i = 0; i < skipped.size(); ++i) s += (i ? ", " : "") + skipped[i];
        detail::svg_text(out, L, H - 10, s, "start", 10, "fill=\"#777\"");
    }
    out += "</svg>\n";
    return out;
}

/// @brief One number of a per-fold plot: `value` of `series` (a method) on `fold`, drawn in `panel` (a metric).
struct fold_point {
    std::string panel, series, fold;
    double value = 0;
};

/// @brief Options of plot_folds_svg.
struct fold_plot_options {
    std::size_t panel_width = 320, panel_height = 240;
    std::size_t panels_per_row = 3;
    std::string title = "per fold";
};

/// @brief Per-fold numbers as small multiples: one panel per `panel` (own linear y axis), the folds in
/// order of first appearance along a shared categorical x axis, one line with dots per series in one colour
/// across every panel (legend on top). Folds are not a time series, so nothing is smoothed. Non-finite
/// values are gaps. Each line has `class="series"` and `data-series`, each legend label `class="legend"`.
/// @throws value_error when `points` is empty.
inline std::string plot_folds_svg(std::span<const fold_point> points, const fold_plot_options& opt = {})
{
    if (points.empty()) throw value_error("plot_folds_svg: no points to draw (expected at least one panel,series,fold,value)");
    std::vector<std::string> panels, series, folds;
    for (const auto& p : points) detail::add_unique(panels, p.panel), detail::add_unique(series, p.series), detail::add_unique(folds, p.fold);
    std::string out;
    const auto fr = detail::open_multiples(out, panels.size(), series, opt.panels_per_row, double(std::max<std::size_t>(opt.panel_width, 160)),
                                           double(std::max<std::size_t>(opt.panel_height, 140)), opt.title, true);
    for (std::size_t k = 0; k < panels.size(); ++k) {
        const auto [ox, oy] = fr.origin(k);
        const double L = ox + 56, R = ox + fr.pw - 14, T = oy + 26, B = oy + fr.ph - 56;
        std::vector<double> vals;
        for (const auto& p : points)
            if (p.panel == panels[k] && std::isfinite(p.value)) vals.push_back(p.value);
        std::vector<double> ticks;
        const detail::y_axis ay = detail::make_y_axis(axis_scale::linear, vals, T, B, ticks);
        auto fx = [&](std::size_t f) {
            return folds.size() == 1 ? (L + R) / 2 : L + 10 + static_cast<double>(f) * (R - L - 20) / static_cast<double>(folds.size() - 1);
        };
        detail::svg_text(out, (L + R) / 2, oy + 16, panels[k], "middle", 13, "font-weight=\"bold\"");
        detail::y_grid(out, ay, ticks, L, R, T, B, "#b0b0b0");
        for (std::size_t f = 0; f < folds.size(); ++f) {
            const double x = fx(f);
            detail::svg_line(out, x, B, x, B + 4, "#444");
            detail::svg_text(out, x - 2, B + 12, folds[f], "end", 10,
                             "transform=\"rotate(-35 " + detail::fmt_px(x - 2) + " " + detail::fmt_px(B + 12) + ")\"");
        }
        out += "<rect x=\"" + detail::fmt_px(L) + "\" y=\"" + detail::fmt_px(T) + "\" width=\"" + detail::fmt_px(R - L) + "\" height=\"" +
               detail::fmt_px(B - T) + "\" fill=\"none\" stroke=\"#444\"/>\n";
        for (std::size_t m = 0; m < series.size(); ++m) {
            const std::string c(detail::plot_palette[m % detail::plot_palette.size()]);
            std::vector<std::pair<double, double>> pts;
            for (std::size_t f = 0; f < folds.size(); ++f)
                for (const auto& p : points)
                    if (p.panel == panels[k] && p.series == series[m] && p.fold == folds[f] && std::isfinite(p.value))
                        pts.emplace_back(fx(f), ay.pixel(p.value));
            if (pts.empty()) continue;
            out += "<polyline class=\"series\" data-series=\"" + detail::xml_escape(series[m]) + "\" fill=\"none\" stroke=\"" + c +
                   "\" stroke-width=\"1.6\" points=\"";
            for (std::size_t i = 0; i < pts.size(); ++i) out += (i ? " " : "") + detail::fmt_px(pts[i].first) + "," + detail::fmt_px(pts[i].second);
            out += "\"><title>" + detail::xml_escape(series[m]) + "</title></polyline>\n";
            for (const auto& p : pts)
                out += "<circle cx=\"" + detail::fmt_px(p.first) + "\" cy=\"" + detail::fmt_px(p.second) + "\" r=\"2.6\" fill=\"" + c + "\"/>\n";
        }
    }
    out += "</svg>\n";
    return out;
}

/// @brief One curve of a track plot: `v[i]` at `t[i]` (t in [0, 1], the clip's normalised time), drawn in `panel`.
struct track_series {
    std::string panel, series;
    std::vector<double> t, v;
};

/// @brief Options of plot_tracks_svg.
struct track_plot_options {
    std::size_t panel_width = 420, panel_height = 220;
    std::size_t panels_per_row = 2;
    std::string title = "tracks";
    std::string y_label = "deg";
};

/// @brief Curves over normalised time as small multiples: one panel per `panel` (own linear y axis, x from 0 to 1),
/// one colour per series across every panel (legend on top). Each curve is a polyline with `class="series"` and
/// `data-series`. Non-finite values break the curve.
/// @throws value_error when `curves` is empty, or a curve's t and v differ in size or t leaves [0, 1].
inline std::string plot_tracks_svg(std::span<const track_series> curves, const track_plot_options& opt = {})
{
    if (curves.empty()) throw value_error("plot_tracks_svg: no curves to draw");
    std::vector<std::string> panels, series;
    for (const auto& c : curves) {
        if (c.t.size() != c.v.size())
            throw value_error("plot_tracks_svg: curve '" + c.series + "' has " + std::to_string(c.t.size()) + " times and " +
                              std::to_string(c.v.size()) + " values");
        for (double t : c.t)
            if (!(t >= 0 && t <= 1)) throw value_error("plot_tracks_svg: curve '" + c.series + "' has a time outside [0, 1]");
        detail::add_unique(panels, c.panel), detail::add_unique(series, c.series);
    }
    std::string out;
    const auto fr = detail::open_multiples(out, panels.size(), series, opt.panels_per_row, double(std::max<std::size_t>(opt.panel_width, 200)),
                                           double(std::max<std::size_t>(opt.panel_height, 140)), opt.title, false);
    for (std::size_t k = 0; k < panels.size(); ++k) {
        const auto [ox, oy] = fr.origin(k);
        const double L = ox + 56, R = ox + fr.pw - 14, T = oy + 26, B = oy + fr.ph - 36;
        std::vector<double> vals;
        for (const auto& c : curves)
            if (c.panel == panels[k])
                for (double v : c.v)
                    if (std::isfinite(v)) vals.push_back(v);
        std::vector<double> ticks;
        const detail::y_axis ay = detail::make_y_axis(axis_scale::linear, vals, T, B, ticks);
        detail::svg_text(out, (L + R) / 2, oy + 16, panels[k], "middle", 13, "font-weight=\"bold\"");
        detail::y_grid(out, ay, ticks, L, R, T, B, "#ececec");
        detail::svg_text(out, ox + 14, (T + B) / 2, opt.y_label, "middle", 10,
                         "transform=\"rotate(-90 " + detail::fmt_px(ox + 14) + " " + detail::fmt_px((T + B) / 2) + ")\"");
        for (double x : {0.0, 0.25, 0.5, 0.75, 1.0}) {
            const double px = L + x * (R - L);
            detail::svg_line(out, px, B, px, B + 4, "#444");
            detail::svg_text(out, px, B + 15, detail::fmt_num(x), "middle", 10);
        }
        out += "<rect x=\"" + detail::fmt_px(L) + "\" y=\"" + detail::fmt_px(T) + "\" width=\"" + detail::fmt_px(R - L) + "\" height=\"" +
               detail::fmt_px(B - T) + "\" fill=\"none\" stroke=\"#444\"/>\n";
        for (std::size_t m = 0; m < series.size(); ++m) {
            const std::string col(detail::plot_palette[m % detail::plot_palette.size()]);
            for (const auto& c : curves) {
                if (c.panel != panels[k] || c.series != series[m]) continue;
                std::string pts;
                auto flush = [&] {
                    if (pts.empty()) return;
                    out += "<polyline class=\"series\" data-series=\"" + detail::xml_escape(series[m]) + "\" fill=\"none\" stroke=\"" + col +
                           "\" stroke-width=\"1.4\" points=\"" + pts + "\"><title>" + detail::xml_escape(series[m]) + "</title></polyline>\n";
                    pts.clear();
                };
                for (std::size_t i = 0; i < c.t.size(); ++i) {
                    if (!std::isfinite(c.v[i])) {
                        flush();
                        continue;
                    }
                    pts += (pts.empty() ? "" : " ") + detail::fmt_px(L + c.t[i] * (R - L)) + "," + detail::fmt_px(ay.pixel(c.v[i]));
                }
                flush();
            }
        }
    }
    out += "</svg>\n";
    return out;
}

/// @brief Parses an evaluation summary CSV with the header `metric,method,mean,std` (std may be empty: 0).
/// @throws format_error naming `what`, the line and the field for a wrong header, field count, a mean
///         that is not a finite number, or a std that is negative or not a number.
inline std::vector<bar_entry> parse_bar_csv(std::string_view text, const std::string& what = "summary")
{
    const auto lines = detail::csv_lines(text);
    if (lines.empty()) throw format_error(what + ": empty file, expected a header 'metric,method,mean,std'");
    const auto h = detail::split_csv_line(lines[0].second);
    std::string hs;
    for (std::size_t i = 0; i < h.size(); ++i) hs += (i ? "," : "") + std::string(h[i]);
    for (auto& ch : hs) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (hs != "metric,method,mean,std")
        throw format_error(what + ": line " + std::to_string(lines[0].first) + ": header '" + std::string(lines[0].second) +
                           "' is not 'metric,method,mean,std'");
    std::vector<bar_entry> out;
    for (std::size_t r = 1; r < lines.size(); ++r) {
        const auto [no, line] = lines[r];
        const auto f = detail::split_csv_line(line);
        if (f.size() != 4)
            throw format_error(what + ": line " + std::to_string(no) + ": " + std::to_string(f.size()) + " fields, expected 4");
        bar_entry e{std::string(f[0]), std::string(f[1]), detail::parse_cell(f[2], what, no, "mean"),
                    detail::parse_cell(f[3], what, no, "std")};
        if (!std::isfinite(e.mean)) throw format_error(what + ": line " + std::to_string(no) + ": mean is empty or not finite");
        if (std::isnan(e.std)) e.std = 0;
        if (!(e.std >= 0) || !std::isfinite(e.std))
            throw format_error(what + ": line " + std::to_string(no) + ": std " + std::string(f[3]) + " is not a finite value >= 0");
        out.push_back(std::move(e));
    }
    if (out.empty()) throw format_error(what + ": no data rows after the header");
    return out;
}

/// @brief True when the first non-blank line of `text` is the header `metric,method,mean,std`.
inline bool is_bar_csv(std::string_view text)
{
    const auto lines = detail::csv_lines(text);
    if (lines.empty()) return false;
    std::string hs;
    const auto h = detail::split_csv_line(lines[0].second);
    for (std::size_t i = 0; i < h.size(); ++i) hs += (i ? "," : "") + std::string(h[i]);
    for (auto& ch : hs) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return hs == "metric,method,mean,std";
}

/// @brief Grouped bar chart: one panel per metric (own linear y axis including 0), one bar per method
/// (same colour in every panel, legend on top), error bars from mean - std to mean + std.
/// @throws value_error when `bars` is empty or a mean/std is not finite (std < 0).
inline std::string plot_bars_svg(std::span<const bar_entry> bars, const bar_plot_options& opt = {})
{
    if (bars.empty()) throw value_error("plot_bars_svg: no bars to draw (expected at least one metric,method,mean,std row)");
    std::vector<std::string> metrics, methods;
    for (const auto& b : bars) {
        if (!std::isfinite(b.mean) || !std::isfinite(b.std) || b.std < 0)
            throw value_error("plot_bars_svg: metric '" + b.metric + "' method '" + b.method + "': mean " + detail::fmt_num(b.mean) +
                              " / std " + detail::fmt_num(b.std) + " must be finite with std >= 0");
        if (std::find(metrics.begin(), metrics.end(), b.metric) == metrics.end()) metrics.push_back(b.metric);
        if (std::find(methods.begin(), methods.end(), b.method) == methods.end()) methods.push_back(b.method);
    }
    const std::size_t per_row = std::max<std::size_t>(1, std::min(opt.panels_per_row, metrics.size()));
    const std::size_t prow = (metrics.size() + per_row - 1) / per_row;
    const double pw = static_cast<double>(std::max<std::size_t>(opt.panel_width, 120)),
                 ph = static_cast<double>(std::max<std::size_t>(opt.panel_height, 120));
    const double legend_h = 22.0 * static_cast<double>((methods.size() + 3) / 4) + 8;
    const double top = 40 + legend_h;
    const double W = pw * static_cast<double>(per_row) + 20, H = top + ph * static_cast<double>(prow) + 10;
    std::string out = detail::svg_open(static_cast<std::size_t>(W), static_cast<std::size_t>(H));
    detail::svg_text(out, W / 2, 24, opt.title, "middle", 16, "font-weight=\"bold\"");
    for (std::size_t m = 0; m < methods.size(); ++m) {
        const double lx = 20 + static_cast<double>(m % 4) * (W - 40) / 4, ly = 44 + 22.0 * static_cast<double>(m / 4);
        out += "<rect x=\"" + detail::fmt_px(lx) + "\" y=\"" + detail::fmt_px(ly - 10) + "\" width=\"14\" height=\"14\" fill=\"" +
               std::string(detail::plot_palette[m % detail::plot_palette.size()]) + "\"/>\n";
        detail::svg_text(out, lx + 20, ly + 2, methods[m], "start", 12);
    }
    for (std::size_t k = 0; k < metrics.size(); ++k) {
        const double ox = 10 + pw * static_cast<double>(k % per_row), oy = top + ph * static_cast<double>(k / per_row);
        const double L = ox + 56, R = ox + pw - 12, T = oy + 26, B = oy + ph - 40;
        std::vector<double> vals{0.0};
        for (const auto& b : bars)
            if (b.metric == metrics[k]) vals.push_back(b.mean - b.std), vals.push_back(b.mean + b.std), vals.push_back(b.mean);
        std::vector<double> ticks;
        const detail::y_axis ay = detail::make_y_axis(axis_scale::linear, vals, T, B, ticks);
        detail::svg_text(out, (L + R) / 2, oy + 16, metrics[k], "middle", 13, "font-weight=\"bold\"");
        for (double t : ticks) {
            const double y = ay.pixel(t);
            detail::svg_line(out, L, y, R, y, t == 0 ? "#888" : "#e4e4e4");
            detail::svg_text(out, L - 6, y + 4, detail::fmt_num(t), "end", 11);
        }
        detail::svg_line(out, L, T, L, B, "#444");
        const double slot = (R - L) / static_cast<double>(methods.size()), bw = slot * 0.7;
        for (std::size_t m = 0; m < methods.size(); ++m) {
            const bar_entry* e = nullptr;
            for (const auto& b : bars)
                if (b.metric == metrics[k] && b.method == methods[m]) e = &b;
            if (!e) continue;
            const double cx = L + slot * (static_cast<double>(m) + 0.5);
            const double y0 = ay.pixel(0), y1 = ay.pixel(e->mean);
            out += "<rect x=\"" + detail::fmt_px(cx - bw / 2) + "\" y=\"" + detail::fmt_px(std::min(y0, y1)) + "\" width=\"" +
                   detail::fmt_px(bw) + "\" height=\"" + detail::fmt_px(std::abs(y1 - y0)) + "\" fill=\"" +
                   std::string(detail::plot_palette[m % detail::plot_palette.size()]) + "\"><title>" +
                   detail::xml_escape(e->method + ": " + detail::fmt_num(e->mean) + " +- " + detail::fmt_num(e->std)) + "</title></rect>\n";
            if (e->std > 0) {
                const double ya = ay.pixel(e->mean - e->std), yb = ay.pixel(e->mean + e->std);
                detail::svg_line(out, cx, ya, cx, yb, "#222", 1.2);
                detail::svg_line(out, cx - bw / 5, ya, cx + bw / 5, ya, "#222", 1.2);
                detail::svg_line(out, cx - bw / 5, yb, cx + bw / 5, yb, "#222", 1.2);
            }
            detail::svg_text(out, cx, B + 14, detail::fmt_num(e->mean, 3), "middle", 10);
        }
    }
    out += "</svg>\n";
    return out;
}

}  // namespace handemo
