// BVH (Biovision Hierarchy) motion files: reads any hierarchy (ROOT/JOINT/End Site, 3 or 6 channels per
// joint in any order) into a `clip`, whose per-joint angle sequences are the P_j of Eq. 1 in Chan, Irimia,
// Ho 2020, and writes a clip back in the conventional layout Blender and three.js import. The reader
// checks everything at the boundary (sizes before allocating, numbers, finiteness, row counts) and names
// the file and 1-based line in every `format_error`; nesting is parsed with an explicit stack, so a
// deeply nested or hostile file cannot overflow the call stack.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/motion/clip.hpp>

#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace handemo {

/// Largest joint count a BVH file may declare; larger hierarchies are refused as corrupt.
inline constexpr std::size_t bvh_max_joints = 10000;

namespace detail {

constexpr bool is_blank(char c) noexcept { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

enum class number_status { ok, not_a_number, not_finite };

/// Parses a whole token as a decimal floating-point number (a leading '+' is accepted).
inline number_status parse_number(std::string_view tok, double& out) noexcept
{
    if (tok.size() > 1 && tok.front() == '+' && tok[1] != '-' && tok[1] != '+') tok.remove_prefix(1);
    if (tok.empty()) return number_status::not_a_number;
    const char* end = tok.data() + tok.size();
    const auto [p, ec] = std::from_chars(tok.data(), end, out);
    if (p != end) return number_status::not_a_number;
    if (ec == std::errc::result_out_of_range) return number_status::not_finite;
    if (ec != std::errc()) return number_status::not_a_number;
    return std::isfinite(out) ? number_status::ok : number_status::not_finite;
}

/// Appends `v` in fixed notation with `decimals` digits after the point, trailing zeros trimmed,
/// "-0" written as "0".
inline void append_fixed(std::string& out, double v, int decimals)
{
    if (decimals < 0) {  // the shortest text that reads back to exactly v (std::to_chars), "-0" as "0"
        char sb[64];
        const auto [q, e] = std::to_chars(sb, sb + sizeof sb, v == 0 ? 0.0 : v);
        if (e != std::errc()) throw value_error("bvh: cannot format value " + std::to_string(v));
        out.append(sb, q);
        return;
    }
    char buf[400];
    const auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
    if (ec != std::errc()) throw value_error("bvh: cannot format value " + std::to_string(v));
    std::string_view s(buf, static_cast<std::size_t>(p - buf));
    if (s.find('.') != std::string_view::npos) {
        while (s.back() == '0') s.remove_suffix(1);
        if (s.back() == '.') s.remove_suffix(1);
    }
    if (s == "-0") s = "0";
    out += s;
}

/// Appends the shortest decimal text that reads back to exactly `v`.
inline void append_shortest(std::string& out, double v)
{
    char buf[64];
    const auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v);
    if (ec != std::errc()) throw value_error("format: cannot format value " + std::to_string(v));
    out.append(buf, p);
}

/// Parses one BVH channel name (case-insensitive), e.g. "Zrotation".
inline bool parse_channel(std::string_view tok, channel& out) noexcept
{
    if (tok.size() != 9) return false;
    auto lower = [](char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; };
    std::string s;
    for (char c : tok) s += lower(c);
    const int a = s[0] == 'x' ? 0 : s[0] == 'y' ? 1 : s[0] == 'z' ? 2 : -1;
    if (a < 0) return false;
    const std::string_view rest = std::string_view(s).substr(1);
    if (rest == "position") out = static_cast<channel>(a);
    else if (rest == "rotation") out = static_cast<channel>(3 + a);
    else return false;
    return true;
}

/// Checks a joint's channel list: 3 rotations (one per axis), optionally 3 positions (one per axis).
/// Returns an empty string when valid, else what is wrong.
inline std::string check_channels(const std::vector<channel>& chans)
{
    if (chans.size() != 3 && chans.size() != 6)
        return "CHANNELS " + std::to_string(chans.size()) + " is not 3 or 6";
    int rot[3] = {0, 0, 0}, pos[3] = {0, 0, 0};
    for (channel c : chans) (is_rotation(c) ? rot : pos)[static_cast<int>(channel_axis(c))]++;
    for (int a = 0; a < 3; ++a) {
        if (rot[a] != 1)
            return std::string("CHANNELS must name ") + "XYZ"[a] + "rotation exactly once, found " +
                   std::to_string(rot[a]);
        if (chans.size() == 6 && pos[a] != 1)
            return std::string("CHANNELS 6 must name ") + "XYZ"[a] + "position exactly once, found " +
                   std::to_string(pos[a]);
    }
    return {};
}

/// Token cursor over BVH text that tracks 1-based line numbers.
class bvh_cursor {
public:
    bvh_cursor(std::string_view text, std::string_view source) : text_(text), src_(source)
    {
        if (text_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;  // UTF-8 byte-order mark
    }

    struct token {
        std::string_view text;
        long line;
    };

    [[noreturn]] void fail(long line, const std::string& msg) const
    {
        throw format_error("bvh: " + where(src_, line) + ": " + msg);
    }

    long line() const noexcept { return line_; }
    bool at_end() const noexcept { return pos_ >= text_.size(); }

    /// Next whitespace-separated token, crossing lines; empty text at end of file.
    token next() noexcept
    {
        while (pos_ < text_.size() && (is_blank(text_[pos_]) || text_[pos_] == '\n')) {
            if (text_[pos_] == '\n') ++line_;
            ++pos_;
        }
        const std::size_t b = pos_;
        while (pos_ < text_.size() && !is_blank(text_[pos_]) && text_[pos_] != '\n') ++pos_;
        return {text_.substr(b, pos_ - b), line_};
    }

    /// Next token, failing with "unexpected end of file <context>" at the end.
    token require(const std::string& context)
    {
        token t = next();
        if (t.text.empty()) fail(line_, "unexpected end of file " + context);
        return t;
    }

    /// The rest of the current line, trimmed (the cursor moves to the line break).
    std::string_view rest_of_line() noexcept
    {
        const std::size_t b = pos_;
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
        std::string_view s = text_.substr(b, pos_ - b);
        while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
        while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
        return s;
    }

    /// Consumes the line break ending the current line (if any) and returns the next line, without
    /// its line break; `line()` is its 1-based number.
    std::string_view next_line() noexcept
    {
        if (pos_ < text_.size() && text_[pos_] == '\n') {
            ++pos_;
            ++line_;
        }
        const std::size_t b = pos_;
        while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
        return text_.substr(b, pos_ - b);
    }

    /// Counts the non-blank lines after the current one, without moving.
    std::size_t count_rows_after() const noexcept
    {
        std::size_t n = 0;
        bool blank = true;
        std::size_t p = pos_;
        while (p < text_.size() && text_[p] != '\n') ++p;  // skip the current line
        for (; p < text_.size(); ++p) {
            const char c = text_[p];
            if (c == '\n') {
                if (!blank) ++n;
                blank = true;
            } else if (!is_blank(c)) {
                blank = false;
            }
        }
        if (!blank) ++n;
        return n;
    }

    double number(const token& t, const std::string& field) const
    {
        double v = 0;
        switch (parse_number(t.text, v)) {
        case number_status::ok: return v;
        case number_status::not_finite:
            fail(t.line, field + ": value '" + std::string(t.text) + "' is not finite");
        default: fail(t.line, field + ": '" + std::string(t.text) + "' is not a number");
        }
    }

private:
    std::string_view text_;
    std::string_view src_;
    std::size_t pos_ = 0;
    long line_ = 1;
};

inline bool is_blank_line(std::string_view s) noexcept
{
    for (char c : s)
        if (!is_blank(c)) return false;
    return true;
}

/// Reads the HIERARCHY section of a BVH file into a skeleton: the ROOT/JOINT/End Site blocks, each with its
/// OFFSET and (joints) CHANNELS, up to and including the MOTION keyword. Open blocks are an explicit stack.
class bvh_hierarchy_reader {
public:
    bvh_hierarchy_reader(bvh_cursor& cur, std::string_view source_name) : cur_(cur) { sk_.name = std::string(source_name); }

    skeleton read()
    {
        auto t = cur_.next();
        if (t.text != "HIERARCHY")
            cur_.fail(t.line, t.text.empty() ? std::string("empty file, expected HIERARCHY")
                                             : "found '" + std::string(t.text) + "', expected HIERARCHY");
        for (t = cur_.next();; t = cur_.next()) {
            if (t.text.empty()) cur_.fail(cur_.line(), "unexpected end of file " + context());
            if (stack_.empty()) {
                if (top_level_item(t)) break;  // MOTION
            } else if (stack_.back().end_site) {
                end_site_item(t);
            } else {
                joint_item(t);
            }
        }
        return std::move(sk_);
    }

private:
    /// An open block: a joint, or that joint's End Site.
    struct open_block {
        int joint;
        bool end_site;
        bool has_offset;
        bool has_channels;
        long line;
    };
    using token = bvh_cursor::token;

    std::string joint_name(int j) const { return "'" + sk_.joints[static_cast<std::size_t>(j)].name + "'"; }

    /// "in HIERARCHY", naming the innermost open block (for "unexpected end of file ...").
    std::string context() const
    {
        if (stack_.empty()) return "in HIERARCHY";
        const auto& b = stack_.back();
        return std::string("in HIERARCHY (") + (b.end_site ? "End Site of joint " : "joint ") + joint_name(b.joint) +
               " opened on line " + std::to_string(b.line) + " is not closed)";
    }

    vec3 read_offset(const std::string& what)
    {
        vec3 v{};
        for (std::size_t k = 0; k < 3; ++k) v[k] = cur_.number(cur_.require(context()), "OFFSET of " + what);
        return v;
    }

    /// After ROOT or JOINT: the name (rest of the line, an optional trailing "{") and the opening brace.
    void open_joint(long line, bool root)
    {
        if (sk_.joints.size() >= bvh_max_joints)
            cur_.fail(line, "more than " + std::to_string(bvh_max_joints) + " joints (corrupt file?)");
        std::string_view name = cur_.rest_of_line();
        bool brace = false;
        if (!name.empty() && name.back() == '{') {
            brace = true;
            name.remove_suffix(1);
            while (!name.empty() && is_blank(name.back())) name.remove_suffix(1);
        }
        if (name.empty()) cur_.fail(line, std::string(root ? "ROOT" : "JOINT") + " has no name");
        if (name.find_first_of("{}") != std::string_view::npos)
            cur_.fail(line, "joint name '" + std::string(name) + "' contains a brace");
        joint j;
        j.name = std::string(name);
        j.parent = root ? -1 : stack_.back().joint;
        j.channels.clear();
        sk_.joints.push_back(std::move(j));
        const int idx = static_cast<int>(sk_.joints.size() - 1);
        if (!brace) {
            auto b = cur_.require(context());
            if (b.text != "{")
                cur_.fail(b.line, "found '" + std::string(b.text) + "' after joint '" + std::string(name) + "', expected {");
        }
        stack_.push_back({idx, false, false, false, line});
    }

    /// Outside any block: ROOT opens one; MOTION ends the hierarchy (returns true).
    bool top_level_item(const token& t)
    {
        if (t.text == "ROOT") {
            open_joint(t.line, true);
        } else if (t.text == "MOTION") {
            if (sk_.joints.empty()) cur_.fail(t.line, "MOTION before any ROOT joint");
            return true;
        } else {
            cur_.fail(t.line, "found '" + std::string(t.text) + "', expected ROOT or MOTION");
        }
        return false;
    }

    /// Inside an End Site: one OFFSET, then "}".
    void end_site_item(const token& t)
    {
        auto& b = stack_.back();
        if (t.text == "OFFSET") {
            if (b.has_offset) cur_.fail(t.line, "second OFFSET in End Site of joint " + joint_name(b.joint));
            sk_.joints[static_cast<std::size_t>(b.joint)].end_site = read_offset("End Site of joint " + joint_name(b.joint));
            b.has_offset = true;
        } else if (t.text == "}") {
            if (!b.has_offset) cur_.fail(t.line, "End Site of joint " + joint_name(b.joint) + " has no OFFSET");
            stack_.pop_back();
        } else {
            cur_.fail(t.line, "found '" + std::string(t.text) + "' in End Site of joint " + joint_name(b.joint) +
                                  ", expected OFFSET or }");
        }
    }

    /// Inside a joint: OFFSET, CHANNELS, child JOINTs (after CHANNELS), one End Site, "}".
    void joint_item(const token& t)
    {
        auto& b = stack_.back();
        joint& jt = sk_.joints[static_cast<std::size_t>(b.joint)];
        if (t.text == "OFFSET") {
            if (b.has_offset) cur_.fail(t.line, "second OFFSET in joint " + joint_name(b.joint));
            jt.offset = read_offset("joint " + joint_name(b.joint));
            b.has_offset = true;
        } else if (t.text == "CHANNELS") {
            if (b.has_channels) cur_.fail(t.line, "second CHANNELS in joint " + joint_name(b.joint));
            read_channels(b.joint, jt);
            b.has_channels = true;
        } else if (t.text == "JOINT") {
            if (!b.has_channels) cur_.fail(t.line, "joint " + joint_name(b.joint) + " has no CHANNELS before JOINT");
            open_joint(t.line, false);  // b and jt are invalid from here
        } else if (t.text == "End") {
            const auto s = cur_.require(context());
            if (s.text != "Site") cur_.fail(s.line, "found 'End " + std::string(s.text) + "', expected End Site");
            if (jt.end_site) cur_.fail(t.line, "second End Site in joint " + joint_name(b.joint));
            const auto br = cur_.require(context());
            if (br.text != "{") cur_.fail(br.line, "found '" + std::string(br.text) + "' after End Site, expected {");
            stack_.push_back({b.joint, true, false, false, t.line});
        } else if (t.text == "}") {
            if (!b.has_offset) cur_.fail(t.line, "joint " + joint_name(b.joint) + " has no OFFSET");
            if (!b.has_channels) cur_.fail(t.line, "joint " + joint_name(b.joint) + " has no CHANNELS");
            stack_.pop_back();
        } else {
            cur_.fail(t.line, "found '" + std::string(t.text) + "' in joint " + joint_name(b.joint) +
                                  ", expected OFFSET, CHANNELS, JOINT, End Site or }");
        }
    }

    /// After CHANNELS: the count (3 or 6) and that many channel names, checked by check_channels().
    void read_channels(int j, joint& jt)
    {
        const auto n = cur_.require(context());
        unsigned count = 0;
        const auto [p, ec] = std::from_chars(n.text.data(), n.text.data() + n.text.size(), count);
        if (ec != std::errc() || p != n.text.data() + n.text.size())
            cur_.fail(n.line, "CHANNELS count '" + std::string(n.text) + "' of joint " + joint_name(j) + " is not a number");
        if (count != 3 && count != 6)
            cur_.fail(n.line, "CHANNELS " + std::string(n.text) + " is not 3 or 6 (joint " + joint_name(j) + ")");
        for (unsigned k = 0; k < count; ++k) {
            const auto c = cur_.require(context());
            channel ch{};
            if (!parse_channel(c.text, ch))
                cur_.fail(c.line, "unknown channel '" + std::string(c.text) + "' in joint " + joint_name(j) +
                                      ", expected Xposition, Yposition, Zposition, Xrotation, Yrotation or "
                                      "Zrotation");
            jt.channels.push_back(ch);
        }
        if (auto msg = check_channels(jt.channels); !msg.empty()) cur_.fail(n.line, msg + " (joint " + joint_name(j) + ")");
    }

    bvh_cursor& cur_;
    skeleton sk_;
    std::vector<open_block> stack_;
};

/// The MOTION header: "Frames: N" and "Frame Time: T".
struct bvh_motion_header {
    std::uint64_t frames = 0;
    long frames_line = 0;  ///< for the messages about the frame count
    double frame_time = 0;
};

/// Reads "Frames: N" (N >= 1; the number may be glued to the colon).
inline void read_bvh_frames(bvh_cursor& cur, bvh_motion_header& h)
{
    auto f = cur.require("after MOTION, expected Frames:");
    h.frames_line = f.line;
    std::string_view frames_text;
    if (f.text.substr(0, 7) == "Frames:") {
        frames_text = f.text.substr(7);
        if (frames_text.empty()) frames_text = cur.require("after Frames:").text;
    } else {
        cur.fail(f.line, "found '" + std::string(f.text) + "', expected Frames:");
    }
    const auto [p, ec] = std::from_chars(frames_text.data(), frames_text.data() + frames_text.size(), h.frames);
    if (ec != std::errc() || p != frames_text.data() + frames_text.size())
        cur.fail(h.frames_line, "Frames: '" + std::string(frames_text) + "' is not a non-negative integer");
    if (h.frames == 0) cur.fail(h.frames_line, "Frames: 0, a clip needs at least one frame");
}

/// Reads "Frame Time: T" (T > 0 with a finite 1 / T; the number may be glued to the colon), alone on its line.
inline void read_bvh_frame_time(bvh_cursor& cur, bvh_motion_header& h)
{
    auto ft = cur.require("after Frames, expected Frame Time:");
    if (ft.text != "Frame") cur.fail(ft.line, "found '" + std::string(ft.text) + "', expected Frame Time:");
    auto tm = cur.require("after Frame, expected Time:");
    std::string_view time_text;
    if (tm.text.substr(0, 5) == "Time:") {
        time_text = tm.text.substr(5);
        if (time_text.empty()) {
            tm = cur.require("after Frame Time:");
            time_text = tm.text;
        }
    } else {
        cur.fail(tm.line, "found 'Frame " + std::string(tm.text) + "', expected Frame Time:");
    }
    h.frame_time = cur.number({time_text, tm.line}, "Frame Time");
    if (!(h.frame_time > 0)) cur.fail(tm.line, "Frame Time " + std::string(time_text) + " is not positive");
    if (!std::isfinite(1.0 / h.frame_time))  // a subnormal such as 1e-310
        cur.fail(tm.line, "Frame Time " + std::string(time_text) + " gives a frame rate of " +
                              std::to_string(1.0 / h.frame_time) + ", expected a finite one");
    if (auto rest = cur.rest_of_line(); !rest.empty())
        cur.fail(cur.line(), "unexpected '" + std::string(rest) + "' after Frame Time");
}

/// Column k of a data row: (joint, channel).
using bvh_column = std::pair<std::size_t, channel>;

inline std::vector<bvh_column> bvh_columns(const skeleton& sk)
{
    std::size_t total = 0;
    for (const auto& j : sk.joints) total += j.channels.size();
    std::vector<bvh_column> columns;
    columns.reserve(total);
    for (std::size_t j = 0; j < sk.joints.size(); ++j)
        for (channel c : sk.joints[j].channels) columns.emplace_back(j, c);
    return columns;
}

/// Parses the values of one data row (line `line`, frame `frame`) into `values`, one per column.
/// @throws format_error for a row with too few or too many values or a value that is not a finite number.
inline void parse_bvh_row(const bvh_cursor& cur, std::string_view row, long line, std::size_t frame, const skeleton& sk,
                          const std::vector<bvh_column>& columns, std::vector<double>& values)
{
    std::size_t k = 0, p = 0;
    for (;;) {
        while (p < row.size() && is_blank(row[p])) ++p;
        if (p >= row.size()) break;
        const std::size_t b = p;
        while (p < row.size() && !is_blank(row[p])) ++p;
        if (k >= columns.size()) {
            std::size_t n = k + 1;  // count all values for the message
            for (;;) {
                while (p < row.size() && is_blank(row[p])) ++p;
                if (p >= row.size()) break;
                while (p < row.size() && !is_blank(row[p])) ++p;
                ++n;
            }
            cur.fail(line, "row has " + std::to_string(n) + " values, expected " + std::to_string(columns.size()));
        }
        const auto [j, ch] = columns[k];
        double v = 0;
        const std::string_view tok = row.substr(b, p - b);
        if (parse_number(tok, v) != number_status::ok)  // slow path: name the field
            (void)cur.number({tok, line}, "frame " + std::to_string(frame) + " joint '" + sk.joints[j].name + "' " +
                                              std::string(channel_name(ch)));
        values[k] = v;
        ++k;
    }
    if (k != columns.size())
        cur.fail(line, "row has " + std::to_string(k) + " values, expected " + std::to_string(columns.size()));
}

/// Appends one frame to `out`: the row's values in their joints' angles or positions, the OFFSET where a joint has
/// no position channels.
inline void append_bvh_frame(clip& out, const std::vector<bvh_column>& columns, const std::vector<double>& values)
{
    const std::size_t J = out.skel.joints.size(), frame = out.frames;
    out.angles.resize(out.angles.size() + J * 3, 0.0);
    for (std::size_t jj = 0; jj < J; ++jj)
        for (std::size_t a = 0; a < 3; ++a) out.positions.push_back(out.skel.joints[jj].offset[a]);
    for (std::size_t c = 0; c < columns.size(); ++c) {
        const auto [j, ch] = columns[c];
        const auto a = static_cast<std::size_t>(channel_axis(ch));
        (is_rotation(ch) ? out.angles : out.positions)[(frame * J + j) * 3 + a] = values[c];
    }
    out.frames = frame + 1;
}

}  // namespace detail

/// @brief Parses BVH text into a clip.
/// @param text the whole file (LF or CRLF line ends, spaces or tabs).
/// @param source_name the file name used in error messages.
/// @return a clip with angles [frames, J, 3] (x, y, z degrees), positions [frames, J, 3] (position
/// channel values, or the joint's OFFSET where it has none) and fps = 1 / Frame Time (snapped to the
/// nearest integer when within 1e-4 relative of it, so `Frame Time: 0.0333333` gives 30 fps).
/// @throws format_error naming the file, 1-based line and field for any malformed, truncated,
/// non-finite, inconsistent (Frames vs rows, values per row) or absurdly large input. Never returns a
/// partial clip.
inline clip parse_bvh(std::string_view text, std::string_view source_name)
{
    detail::bvh_cursor cur(text, source_name);
    skeleton sk = detail::bvh_hierarchy_reader(cur, source_name).read();
    detail::bvh_motion_header h;
    detail::read_bvh_frames(cur, h);
    detail::read_bvh_frame_time(cur, h);

    // Count the data rows before allocating anything sized by Frames.
    const std::size_t rows = cur.count_rows_after();
    if (rows != h.frames)
        cur.fail(h.frames_line, "Frames: " + std::to_string(h.frames) + " but the file has " + std::to_string(rows) +
                                    " data row" + (rows == 1 ? "" : "s") +
                                    (rows < h.frames ? " (truncated motion?)" : " (extra rows?)"));

    // The clip grows one frame per parsed row (never sized from Frames or the row count: a row that is
    // one short token must not reserve J*3 values), and its frame count is checked against Frames at the end.
    const std::vector<detail::bvh_column> columns = detail::bvh_columns(sk);
    clip out = clip::make(std::move(sk), 0, 1.0 / h.frame_time);
    if (const double r = std::round(out.fps); r >= 1 && std::abs(out.fps - r) <= 1e-4 * r) out.fps = r;
    std::vector<double> values(columns.size());
    while (out.frames < h.frames && !cur.at_end()) {
        const std::string_view row = cur.next_line();
        if (detail::is_blank_line(row)) continue;
        detail::parse_bvh_row(cur, row, cur.line(), out.frames, out.skel, columns, values);
        detail::append_bvh_frame(out, columns, values);
    }
    if (out.frames != h.frames)
        cur.fail(h.frames_line, "Frames: " + std::to_string(h.frames) + " but the file has " + std::to_string(out.frames) +
                                    " data row" + (out.frames == 1 ? "" : "s") + " (truncated motion?)");
    return out;
}

/// @brief Reads a BVH file.
/// @throws io_error when the file cannot be read; format_error (file, line, field) when it is malformed.
inline clip read_bvh(const std::filesystem::path& path) { return parse_bvh(read_file(path), path.string()); }

/// @brief Formats a clip as BVH text: HIERARCHY with ROOT/JOINT/End Site blocks indented by tabs,
/// channels in each joint's stored order, then MOTION, Frames:, Frame Time: and one row per frame.
/// Joints are written depth-first from the parent indices (the clip's order when it came from a file).
/// @param precision digits after the decimal point for OFFSET and motion values (0..17), or -1 for the shortest
/// text that reads back to exactly the same double (a clip read from a file is then written with its values
/// unchanged to the bit).
/// @throws value_error / shape_error when the clip is inconsistent (see clip::validate), a joint's
/// channels are not 3 rotations (+ 3 positions) or a name cannot be written.
inline std::string to_bvh_string(const clip& c, int precision = 6)
{
    c.validate("to_bvh_string");
    if (precision < -1 || precision > 17)
        throw value_error("to_bvh_string: precision " + std::to_string(precision) + " is not in -1..17");
    const skeleton& sk = c.skel;
    const std::size_t J = sk.size();
    std::vector<std::vector<std::size_t>> children(J);
    std::vector<std::size_t> roots;
    for (std::size_t j = 0; j < J; ++j) {
        const joint& jt = sk.joints[j];
        if (auto msg = detail::check_channels(jt.channels); !msg.empty())
            throw value_error("to_bvh_string: joint '" + jt.name + "': " + msg);
        if (jt.name.empty() || jt.name.find_first_of("{}\r\n") != std::string::npos ||
            detail::is_blank(jt.name.front()) || detail::is_blank(jt.name.back()))
            throw value_error("to_bvh_string: joint " + std::to_string(j) + " name '" + jt.name +
                              "' is empty or has braces, line breaks or surrounding blanks");
        if (jt.parent < 0) roots.push_back(j);
        else children[static_cast<std::size_t>(jt.parent)].push_back(j);
    }

    // Depth-first pre-order with an explicit stack.
    std::vector<std::pair<std::size_t, std::size_t>> order;  // (joint, depth)
    order.reserve(J);
    {
        std::vector<std::pair<std::size_t, std::size_t>> st;
        for (auto r = roots.rbegin(); r != roots.rend(); ++r) st.emplace_back(*r, 0);
        while (!st.empty()) {
            const auto [j, d] = st.back();
            st.pop_back();
            order.emplace_back(j, d);
            for (auto ch = children[j].rbegin(); ch != children[j].rend(); ++ch) st.emplace_back(*ch, d + 1);
        }
    }

    std::string s;
    s.reserve(64 * J + c.frames * J * 6 * 10);
    auto indent = [&](std::size_t d) { s.append(d, '\t'); };
    auto vec = [&](const vec3& v) {
        for (std::size_t k = 0; k < 3; ++k) {
            s += ' ';
            detail::append_fixed(s, v[k], precision);
        }
    };
    std::vector<std::size_t> open;  // joints whose block is open
    auto close = [&]() {
        const std::size_t j = open.back();
        const std::size_t d = open.size() - 1;
        if (sk.joints[j].end_site) {
            indent(d + 1), s += "End Site\n";
            indent(d + 1), s += "{\n";
            indent(d + 2), s += "OFFSET", vec(*sk.joints[j].end_site), s += '\n';
            indent(d + 1), s += "}\n";
        }
        indent(d), s += "}\n";
        open.pop_back();
    };
    s += "HIERARCHY\n";
    for (const auto& [j, d] : order) {
        while (open.size() > d) close();
        const joint& jt = sk.joints[j];
        indent(d), s += (d == 0 ? "ROOT " : "JOINT "), s += jt.name, s += '\n';
        indent(d), s += "{\n";
        indent(d + 1), s += "OFFSET", vec(jt.offset), s += '\n';
        indent(d + 1), s += "CHANNELS ", s += std::to_string(jt.channels.size());
        for (channel ch : jt.channels) s += ' ', s += channel_name(ch);
        s += '\n';
        open.push_back(j);
    }
    while (!open.empty()) close();

    s += "MOTION\nFrames:\t" + std::to_string(c.frames) + "\nFrame Time:\t";
    {
        char buf[64];
        const auto [p, ec] = std::to_chars(buf, buf + sizeof buf, 1.0 / c.fps, std::chars_format::general, 10);
        (void)ec;
        s.append(buf, p);
    }
    s += '\n';
    for (std::size_t f = 0; f < c.frames; ++f) {
        bool first = true;
        for (const auto& [j, d] : order) {
            for (channel ch : sk.joints[j].channels) {
                if (!first) s += ' ';
                first = false;
                const auto a = static_cast<std::size_t>(channel_axis(ch));
                detail::append_fixed(s, is_rotation(ch) ? c.angle(f, j, a) : c.position(f, j, a), precision);
            }
        }
        s += '\n';
    }
    return s;
}

/// @brief Writes a clip as a BVH file atomically (temporary file + rename).
/// @throws value_error / shape_error for an inconsistent clip, io_error when the file cannot be written.
inline void write_bvh(const std::filesystem::path& path, const clip& c, int precision = 6)
{
    write_file_atomic(path, to_bvh_string(c, precision));
}

}  // namespace handemo
