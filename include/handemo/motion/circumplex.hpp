// Russell's circumplex (valence x arousal, both in [-1, 1]): the coordinates of emotion labels, read from a JSON
// data file with its citation (data/rcm/circumplex.json: Warriner, Kuperman & Brysbaert 2013 word norms rescaled
// from 1..9 to [-1, 1]), paths of waypoints on it, and the interpolation over the labels' points that makes a
// per-emotion quantity a function of any point of the unit disc (circumplex_interpolation: weights that sum to
// one, are exact at the labels and linear along every straight line from neutral to a label; docs/continuous.md).
// Both the circumplex method (rcm/) and the StarGAN transfer's continuous control (stargan/continuous.hpp) use it.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace handemo {

/// @brief A named point of the circumplex.
struct label_point {
    std::string name;
    double valence = 0, arousal = 0;  ///< both in [-1, 1]
};

/// @brief Quadrant of a point: 1 (valence >= 0, arousal >= 0, e.g. happy), 2 (negative valence, high
/// arousal: angry), 3 (negative, low: sad), 4 (positive valence, low arousal: relaxed).
constexpr int quadrant(double valence, double arousal) noexcept
{
    return valence >= 0 ? (arousal >= 0 ? 1 : 4) : (arousal >= 0 ? 2 : 3);
}

/// @brief Label coordinates of a circumplex file, plus its citation.
struct circumplex_table {
    std::string source;
    std::vector<label_point> labels;

    /// @brief The point of a label.
    /// @throws value_error naming the label, the file and the known labels.
    const label_point& at(const std::string& name, const std::string& what = "circumplex table") const
    {
        for (const auto& l : labels)
            if (l.name == name) return l;
        std::string known;
        for (const auto& l : labels) known += (known.empty() ? "" : ", ") + l.name;
        throw value_error("rcm: label '" + name + "' has no circumplex coordinates in " + what + " (known: " + known + ")");
    }
};

/// @brief Parses a circumplex file: `{"format": "handemo-rcm-circumplex", "version": 1, "source": "...",
/// "labels": {"happy": {"valence_1_9": 8.47, "arousal_1_9": 6.05}, ...}}` (or `valence`/`arousal` in [-1, 1]).
/// @throws format_error naming `what` and the field.
inline circumplex_table parse_circumplex(const std::string& text, const std::string& what)
{
    nlohmann::json j;
    try {
        j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        throw format_error("rcm circumplex: " + what + ": not JSON: " + e.what());
    }
    auto need = [&](const nlohmann::json& o, const char* key, const std::string& where) -> const nlohmann::json& {
        if (!o.is_object() || !o.contains(key)) throw format_error("rcm circumplex: " + what + ": missing field '" + where + key + "'");
        return o.at(key);
    };
    if (need(j, "format", "") != "handemo-rcm-circumplex")
        throw format_error("rcm circumplex: " + what + ": field 'format' is not \"handemo-rcm-circumplex\"");
    if (need(j, "version", "") != 1) throw format_error("rcm circumplex: " + what + ": field 'version' is not 1");
    circumplex_table t;
    const auto& src = need(j, "source", "");
    if (!src.is_string() || src.get<std::string>().empty()) throw format_error("rcm circumplex: " + what + ": field 'source' (the citation) is empty");
    t.source = src.get<std::string>();
    const auto& labels = need(j, "labels", "");
    if (!labels.is_object() || labels.empty()) throw format_error("rcm circumplex: " + what + ": field 'labels' is not a non-empty object");
    for (const auto& item : labels.items()) {
        // not a structured binding: clang 14 cannot capture one in the lambda below
        const std::string& name = item.key();
        const nlohmann::json& v = item.value();
        label_point p;
        p.name = name;
        const std::string w = "labels." + name + ".";
        auto num = [&](const char* key) {
            const auto& x = need(v, key, w);
            if (!x.is_number()) throw format_error("rcm circumplex: " + what + ": field '" + w + key + "' is not a number");
            return x.get<double>();
        };
        if (v.is_object() && v.contains("valence_1_9")) {
            const double va = num("valence_1_9"), ar = num("arousal_1_9");
            if (va < 1 || va > 9 || ar < 1 || ar > 9) throw format_error("rcm circumplex: " + what + ": field '" + w + "' rating outside 1..9");
            p.valence = (va - 5) / 4;
            p.arousal = (ar - 5) / 4;
        } else {
            p.valence = num("valence");
            p.arousal = num("arousal");
            if (std::abs(p.valence) > 1 || std::abs(p.arousal) > 1)
                throw format_error("rcm circumplex: " + what + ": field '" + w + "' outside [-1, 1]");
        }
        t.labels.push_back(p);
    }
    return t;
}

/// @brief Reads a circumplex file (parse_circumplex()).
inline circumplex_table load_circumplex(const std::filesystem::path& path) { return parse_circumplex(read_file(path), path.string()); }

/// @brief One point of a circumplex path.
struct path_point {
    std::string name;  ///< the label, `V:A` for an explicit point, or empty for a point between waypoints
    double valence = 0, arousal = 0;
    bool waypoint = false;  ///< one of the points the path was given (not one sampled between them)
};

/// @brief Parses a path `sad,neutral,happy` or `-0.7:-0.4,(0.1,-0.4),happy`: waypoints separated by commas,
/// each a label of `labels` or an explicit point `V:A` or `(V,A)` with V and A in [-1, 1].
/// `what` starts every message (the command or function that parses).
/// @throws value_error naming the bad waypoint (an unknown label lists the known ones).
inline std::vector<path_point> parse_path(const std::string& text, const std::vector<label_point>& labels,
                                          const std::string& what = "circumplex path")
{
    std::vector<std::string> tokens;
    std::string cur;
    int depth = 0;
    for (char ch : text) {
        if (ch == '(') ++depth;
        if (ch == ')') --depth;
        if (ch == ',' && depth == 0) {
            tokens.push_back(cur);
            cur.clear();
        } else {
            cur += ch;
        }
        if (depth < 0) throw value_error(what + ": '" + text + "': ')' without '('");
    }
    if (depth != 0) throw value_error(what + ": '" + text + "': '(' without ')'");
    tokens.push_back(cur);
    auto trim = [](std::string s) {
        const auto b = s.find_first_not_of(" \t"), e = s.find_last_not_of(" \t");
        return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
    };
    auto number = [&](const std::string& s, const std::string& tok) {
        const std::string t = trim(s);
        char* end = nullptr;
        const double v = std::strtod(t.c_str(), &end);
        if (t.empty() || end != t.c_str() + t.size() || !std::isfinite(v))
            throw value_error(what + ": waypoint '" + tok + "': '" + t + "' is not a number");
        if (std::abs(v) > 1) throw value_error(what + ": waypoint '" + tok + "': " + t + " is outside [-1, 1]");
        return v;
    };
    std::vector<path_point> out;
    for (const auto& raw : tokens) {
        const std::string tok = trim(raw);
        if (tok.empty()) throw value_error(what + ": '" + text + "' has an empty waypoint");
        path_point p;
        p.waypoint = true;
        p.name = tok;
        std::string body = tok;
        char sep = ':';
        if (body.front() == '(') {
            if (body.back() != ')') throw value_error(what + ": waypoint '" + tok + "' does not end with ')'");
            body = body.substr(1, body.size() - 2);
            sep = ',';
        }
        const auto at = body.find(sep);
        if (tok.front() == '(' || at != std::string::npos) {
            if (at == std::string::npos || body.find(sep, at + 1) != std::string::npos)
                throw value_error(what + ": waypoint '" + tok + "' is not two numbers V" + std::string(1, sep) + "A");
            p.valence = number(body.substr(0, at), tok);
            p.arousal = number(body.substr(at + 1), tok);
        } else {
            const auto it = std::find_if(labels.begin(), labels.end(), [&](const label_point& l) { return l.name == tok; });
            if (it == labels.end()) {
                std::string known;
                for (const auto& l : labels) known += (known.empty() ? "" : ", ") + l.name;
                throw value_error(what + ": waypoint '" + tok + "' is not a label with coordinates (known: " + known +
                                  ") nor a point V:A");
            }
            p.valence = it->valence, p.arousal = it->arousal;
        }
        out.push_back(p);
    }
    return out;
}

/// @brief Samples a polyline through `waypoints`: each segment gives `steps` points (its start and steps - 1
/// evenly spaced points before its end), then the last waypoint, so every waypoint is a sample and there are
/// (W - 1) steps + 1 samples.
/// @throws value_error for no waypoints or steps == 0.
inline std::vector<path_point> sample_path(const std::vector<path_point>& waypoints, std::size_t steps, const std::string& what = "circumplex path")
{
    if (waypoints.empty()) throw value_error(what + ": no waypoints");
    if (steps == 0) throw value_error(what + ": --steps must be at least 1");
    std::vector<path_point> out;
    for (std::size_t w = 0; w + 1 < waypoints.size(); ++w) {
        const auto &a = waypoints[w], &b = waypoints[w + 1];
        out.push_back(a);
        for (std::size_t s = 1; s < steps; ++s) {
            const double t = static_cast<double>(s) / static_cast<double>(steps);
            path_point p;
            p.valence = a.valence + t * (b.valence - a.valence);
            p.arousal = a.arousal + t * (b.arousal - a.arousal);
            out.push_back(p);
        }
    }
    out.push_back(waypoints.back());
    return out;
}

/// @brief A short title for a path point: `sad` or `(0.30,-0.10)`.
inline std::string path_title(const path_point& p)
{
    char b[48];
    std::snprintf(b, sizeof b, "(%.2f,%.2f)", p.valence, p.arousal);
    if (p.name.empty() || p.name.find(':') != std::string::npos || p.name.front() == '(') return b;
    return p.name;
}

/// @brief The interpolation of per-emotion quantities over the circumplex: weights w_l(V, A), one per label,
/// that make any per-label quantity x_l a function of a point, x(V, A) = sum_l w_l(V, A) x_l.
///
/// Neutral is the centre of the dial and every other label a spoke from it. A point p is read in polar
/// coordinates about neutral's point N: its direction picks the two labels whose directions bracket it (angular
/// neighbours a and b), and the ray from N through p meets the outline joining them (the straight edge from a's
/// point to b's, or, across an angle of 180 degrees or more where no label lies, the arc whose radius goes
/// linearly from a's distance to b's). With lambda the place where the ray meets that outline (0 at a, 1 at b)
/// and s = min(1, |p - N| / (distance from N to the outline along the ray)):
///
///     w_a = s (1 - lambda),   w_b = s lambda,   w_neutral = 1 - s,   every other weight 0.
///
/// So the weights are never negative and sum to one; at a label's own point they are exactly 1 for it and 0 for
/// every other; on the straight line from N to a label they are (1 - t, t) for that label and neutral; inside
/// the triangle (N, a, b) they are its barycentric coordinates (sum_l w_l c_l = p there); beyond the outline
/// they keep the outline's blend (no extrapolation past what a label showed); and they are Lipschitz continuous
/// on the whole disc (up to the snap to a label's point within snap_distance). docs/continuous.md gives the reasons.
class circumplex_interpolation {
public:
    /// @param labels the labels' points, in the order the weights are wanted in (a model's domains)
    /// @param neutral the index of the neutral label in `labels`
    /// @throws value_error for fewer than two labels, a neutral index out of range, a label outside the unit
    /// circle or on neutral's point, or two labels on one ray from neutral (their blend would be undefined),
    /// naming them.
    circumplex_interpolation(std::vector<label_point> labels, std::size_t neutral) : labels_(std::move(labels)), neutral_(neutral)
    {
        if (labels_.size() < 2) throw value_error("circumplex interpolation: " + std::to_string(labels_.size()) + " labels, expected neutral and at least one other");
        if (neutral_ >= labels_.size()) throw value_error("circumplex interpolation: neutral index " + std::to_string(neutral_) + " out of range");
        const auto& n = labels_[neutral_];
        for (std::size_t i = 0; i < labels_.size(); ++i) {
            const auto& l = labels_[i];
            if (!std::isfinite(l.valence) || !std::isfinite(l.arousal) || std::hypot(l.valence, l.arousal) > 1)
                throw value_error("circumplex interpolation: label '" + l.name + "' is not a point of the unit circle");
            if (i == neutral_) continue;
            spoke s;
            s.label = i;
            s.dx = l.valence - n.valence;
            s.dy = l.arousal - n.arousal;
            s.r = std::hypot(s.dx, s.dy);
            s.theta = std::atan2(s.dy, s.dx);
            if (!(s.r > 1e-9))
                throw value_error("circumplex interpolation: label '" + l.name + "' sits on neutral's point ('" + n.name + "'): no direction to blend along");
            spokes_.push_back(s);
        }
        std::sort(spokes_.begin(), spokes_.end(), [](const spoke& a, const spoke& b) { return a.theta < b.theta; });
        for (std::size_t i = 0; i + 1 < spokes_.size(); ++i)
            if (spokes_[i + 1].theta - spokes_[i].theta < 1e-9)
                throw value_error("circumplex interpolation: labels '" + labels_[spokes_[i].label].name + "' and '" + labels_[spokes_[i + 1].label].name +
                                  "' lie on one ray from neutral: their blend is undefined");
    }

    /// Points this close to a label's point take its weights exactly (far below any meaningful difference of
    /// valence or arousal; far above the rounding of decimal coordinates).
    static constexpr double snap_distance = 1e-9;

    const std::vector<label_point>& labels() const noexcept { return labels_; }
    std::size_t neutral() const noexcept { return neutral_; }

    /// @brief Whether (V, A) is a point of the closed unit disc (both finite).
    static bool inside(double valence, double arousal) noexcept
    {
        return std::isfinite(valence) && std::isfinite(arousal) && valence * valence + arousal * arousal <= 1.0 + 1e-12;
    }

    /// @brief Throws unless (V, A) is a point of the closed unit disc. `what` starts the message.
    static void check_point(double valence, double arousal, const std::string& what)
    {
        if (inside(valence, arousal)) return;
        char b[160];
        std::snprintf(b, sizeof b, ": the point (valence %g, arousal %g) lies outside the circumplex (radius %.4g > 1)", valence, arousal,
                      std::hypot(valence, arousal));
        throw value_error(what + b);
    }

    /// @brief The weights of (V, A), one per label in the constructor's order.
    /// @throws value_error for a point outside the unit disc.
    std::vector<double> weights(double valence, double arousal) const
    {
        std::vector<double> w;
        weights_into(valence, arousal, w);
        return w;
    }

    /// @brief weights() into `w` (its storage reused).
    void weights_into(double valence, double arousal, std::vector<double>& w) const
    {
        check_point(valence, arousal, "circumplex interpolation");
        w.assign(labels_.size(), 0.0);
        // a point within snap_distance of a label's is that label's: decimals typed for a label's coordinates
        // (-0.725, -0.3775 for sad) are its point, and its transfer exactly
        for (std::size_t l = 0; l < labels_.size(); ++l)
            if (std::hypot(valence - labels_[l].valence, arousal - labels_[l].arousal) <= snap_distance) {
                w[l] = 1;
                return;
            }
        const auto& n = labels_[neutral_];
        const double dx = valence - n.valence, dy = arousal - n.arousal, r = std::hypot(dx, dy);
        if (r == 0) {
            w[neutral_] = 1;
            return;
        }
        const double theta = std::atan2(dy, dx);
        // a point on a spoke (a label's own direction): the line from neutral to that label, exact at its point
        for (const auto& s : spokes_)
            if (theta == s.theta) {
                const double t = std::min(1.0, r / s.r);
                w[s.label] = t;
                w[neutral_] = 1 - t;
                return;
            }
        // the angular neighbours: a (the last spoke at or before theta, cyclically) and b (the next)
        std::size_t ib = 0;
        while (ib < spokes_.size() && spokes_[ib].theta < theta) ++ib;
        const spoke& b = spokes_[ib % spokes_.size()];
        const spoke& a = spokes_[(ib + spokes_.size() - 1) % spokes_.size()];
        const double two_pi = 2 * std::numbers::pi;
        double gap = b.theta - a.theta, off = theta - a.theta;
        if (gap <= 0) gap += two_pi;  // the gap across -pi (or a single spoke: all around)
        if (off < 0) off += two_pi;
        double lambda = 0, rho = 0;
        if (gap < std::numbers::pi) {
            // the straight edge a -> b: p = N + rho u meets a + lambda (b - a)
            const double ux = dx / r, uy = dy / r, ex = b.dx - a.dx, ey = b.dy - a.dy;
            const double den = ux * ey - uy * ex;
            rho = (a.dx * ey - a.dy * ex) / den;
            lambda = (a.dx * uy - a.dy * ux) / den;
        } else {
            // no label within 180 degrees on this side: the arc from a to b, its radius linear in the angle
            lambda = off / gap;
            rho = (1 - lambda) * a.r + lambda * b.r;
        }
        lambda = std::clamp(lambda, 0.0, 1.0);
        const double s = std::min(1.0, r / rho);
        w[a.label] += s * (1 - lambda);
        w[b.label] += s * lambda;
        w[neutral_] = 1 - s;
    }

private:
    struct spoke {
        std::size_t label = 0;
        double dx = 0, dy = 0, r = 0, theta = 0;
    };
    std::vector<label_point> labels_;
    std::size_t neutral_ = 0;
    std::vector<spoke> spokes_;
};

/// @brief The points of an n x n grid over [-1, 1]^2 that lie in the closed unit disc (inside()): valence
/// v_j = (2 j - (n - 1)) / (n - 1) and arousal a_i likewise, for i, j in 0..n-1, row by row from the lowest arousal,
/// valence increasing within a row. The axis ends (+-1, 0), (0, +-1) are exact, and an odd n holds the centre.
/// @throws value_error for n outside 3..101 (n = 2 would hold only the four corners, none in the disc).
inline std::vector<std::pair<double, double>> va_grid(std::size_t n)
{
    if (n < 3 || n > 101) throw value_error("va_grid: grid size " + std::to_string(n) + " is not in 3..101");
    const double m = static_cast<double>(n - 1);
    std::vector<std::pair<double, double>> out;
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = 0; j < n; ++j) {
            const double v = (2.0 * static_cast<double>(j) - m) / m, a = (2.0 * static_cast<double>(i) - m) / m;
            if (circumplex_interpolation::inside(v, a)) out.emplace_back(v, a);
        }
    return out;
}

/// @brief A target that moves over time: (valence, arousal) at increasing times in seconds, linear between
/// rows and held before the first and after the last.
struct va_curve {
    std::vector<double> time, valence, arousal;

    std::size_t size() const noexcept { return time.size(); }

    /// @brief The point at time `t` (seconds).
    std::pair<double, double> at(double t) const
    {
        if (time.empty()) throw value_error("circumplex curve: no points");
        if (t <= time.front()) return {valence.front(), arousal.front()};
        if (t >= time.back()) return {valence.back(), arousal.back()};
        const std::size_t i = static_cast<std::size_t>(std::upper_bound(time.begin(), time.end(), t) - time.begin()) - 1;
        const double u = (t - time[i]) / (time[i + 1] - time[i]);
        return {valence[i] + u * (valence[i + 1] - valence[i]), arousal[i] + u * (arousal[i + 1] - arousal[i])};
    }
};

/// @brief Parses a curve file: one row `time,valence,arousal` per line (seconds, then both in [-1, 1] within the
/// unit circle), times strictly increasing; an optional first line of column names; empty lines and lines
/// starting with '#' are skipped. `what` (the file name) is in every message, with the line.
/// @throws format_error naming the file and line of a bad row (not three numbers, a time not after the
/// previous one, a point outside the circle) or a file without rows.
inline va_curve parse_va_curve(const std::string& text, const std::string& what)
{
    va_curve c;
    std::size_t line_no = 0, pos = 0;
    bool first = true;
    while (pos <= text.size()) {
        std::size_t e = text.find('\n', pos);
        if (e == std::string::npos) e = text.size();
        std::string line = text.substr(pos, e - pos);
        pos = e + 1;
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        const auto b = line.find_first_not_of(" \t");
        if (b == std::string::npos || line[b] == '#') {
            if (e == text.size()) break;
            continue;
        }
        const std::string where = "circumplex curve: " + what + ": line " + std::to_string(line_no);
        std::vector<std::string> cells;
        std::size_t q = 0;
        while (true) {
            const auto comma = line.find(',', q);
            cells.push_back(line.substr(q, comma == std::string::npos ? std::string::npos : comma - q));
            if (comma == std::string::npos) break;
            q = comma + 1;
        }
        double v[3] = {0, 0, 0};
        bool numbers = cells.size() == 3;
        for (std::size_t k = 0; numbers && k < 3; ++k) {
            std::string s = cells[k];
            const auto sb = s.find_first_not_of(" \t"), se = s.find_last_not_of(" \t");
            s = sb == std::string::npos ? std::string() : s.substr(sb, se - sb + 1);
            char* end = nullptr;
            v[k] = std::strtod(s.c_str(), &end);
            numbers = !s.empty() && end == s.c_str() + s.size() && std::isfinite(v[k]);
        }
        if (!numbers) {
            if (first && cells.size() == 3) {  // column names
                first = false;
                if (e == text.size()) break;
                continue;
            }
            throw format_error(where + ": expected three numbers time,valence,arousal, found '" + line + "'");
        }
        first = false;
        if (!c.time.empty() && !(v[0] > c.time.back()))
            throw format_error(where + ": time " + cells[0] + " is not after the previous row's");
        if (!circumplex_interpolation::inside(v[1], v[2])) {
            try {
                circumplex_interpolation::check_point(v[1], v[2], where);
            } catch (const value_error& x) {
                throw format_error(x.what());
            }
        }
        c.time.push_back(v[0]);
        c.valence.push_back(v[1]);
        c.arousal.push_back(v[2]);
        if (e == text.size()) break;
    }
    if (c.time.empty()) throw format_error("circumplex curve: " + what + ": no rows time,valence,arousal");
    return c;
}

/// @brief Reads a curve file (parse_va_curve()). @throws io_error, format_error naming the file.
inline va_curve read_va_curve(const std::filesystem::path& path) { return parse_va_curve(read_file(path), path.string()); }

/// @brief The curve through `waypoints` in `duration` seconds: waypoint i at i duration / (W - 1) (one waypoint:
/// held the whole time), straight lines between them.
/// @throws value_error for no waypoints, a duration that is not positive, or a waypoint outside the circle.
inline va_curve path_curve(const std::vector<path_point>& waypoints, double duration, const std::string& what = "circumplex path")
{
    if (waypoints.empty()) throw value_error(what + ": no waypoints");
    if (!(duration > 0) || !std::isfinite(duration)) throw value_error(what + ": duration " + std::to_string(duration) + " s is not positive");
    va_curve c;
    for (std::size_t i = 0; i < waypoints.size(); ++i) {
        const auto& p = waypoints[i];
        circumplex_interpolation::check_point(p.valence, p.arousal, what + ": waypoint '" + p.name + "'");
        c.time.push_back(waypoints.size() == 1 ? 0.0 : duration * static_cast<double>(i) / static_cast<double>(waypoints.size() - 1));
        c.valence.push_back(p.valence);
        c.arousal.push_back(p.arousal);
    }
    return c;
}

}  // namespace handemo
