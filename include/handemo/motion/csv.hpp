// CSV motion files: one row per frame, one column per joint-angle component, so a clip (the P_j
// sequences of Eq. 1 in Chan, Irimia, Ho 2020) can be inspected in a spreadsheet or plotted. Layout:
//
//     # fps=30
//     frame,Hips_px,Hips_py,Hips_pz,Hips_x,Hips_y,Hips_z,Spine_x,Spine_y,Spine_z,...
//     0,0.5,93.5,-9.0,88.9,-5.1,4.5,...
//
// The first line is a comment `# fps=<frames per second>` (optional when reading: 30 is assumed when it
// is absent; other `#` lines are ignored). `frame` is the 0-based frame index. `<joint>_x/_y/_z` are the
// joint's rotation angles in degrees about x, y, z (whatever the BVH channel order); joints with
// position channels also have `<joint>_px/_py/_pz`. The joint name is everything before the last `_`,
// so names may themselves contain underscores. The reader matches columns to joints by name, in any
// column order; the skeleton (offsets, channel orders) comes from a reference, usually a BVH file.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/io.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/clip.hpp>

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

namespace handemo {

namespace detail {

inline std::string_view trim_blanks(std::string_view s) noexcept
{
    while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
    while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
    return s;
}

/// Splits a CSV line at commas (no quoting: handemo never writes commas inside fields), trimming blanks.
inline void split_csv(std::string_view line, std::vector<std::string_view>& out)
{
    out.clear();
    std::size_t b = 0;
    for (;;) {
        const std::size_t e = line.find(',', b);
        out.push_back(trim_blanks(line.substr(b, e == std::string_view::npos ? std::string_view::npos : e - b)));
        if (e == std::string_view::npos) break;
        b = e + 1;
    }
}

[[noreturn]] inline void csv_fail(std::string_view source, long line, const std::string& msg)
{
    throw format_error("csv: " + where(source, line) + ": " + msg);
}

}  // namespace detail

/// @brief Formats a clip as CSV (see the file comment for the layout); values are written in the
/// shortest form that reads back exactly.
/// @throws value_error / shape_error for an inconsistent clip or a joint name containing a comma,
/// quote or line break.
inline std::string to_csv_string(const clip& c)
{
    c.validate("to_csv_string");
    const std::size_t J = c.skel.size();
    std::string s = "# fps=";
    detail::append_shortest(s, c.fps);
    s += "\nframe";
    for (const joint& j : c.skel.joints) {
        if (j.name.empty() || j.name.find_first_of(",\"\r\n#") != std::string::npos)
            throw value_error("to_csv_string: joint name '" + j.name + "' is empty or has a comma, quote, # or line break");
        if (j.has_position()) s += "," + j.name + "_px," + j.name + "_py," + j.name + "_pz";
        s += "," + j.name + "_x," + j.name + "_y," + j.name + "_z";
    }
    s += '\n';
    for (std::size_t f = 0; f < c.frames; ++f) {
        s += std::to_string(f);
        for (std::size_t j = 0; j < J; ++j) {
            if (c.skel.joints[j].has_position())
                for (std::size_t k = 0; k < 3; ++k) s += ',', detail::append_shortest(s, c.position(f, j, k));
            for (std::size_t k = 0; k < 3; ++k) s += ',', detail::append_shortest(s, c.angle(f, j, k));
        }
        s += '\n';
    }
    return s;
}

/// @brief Writes a clip as CSV atomically (temporary file + rename).
/// @throws value_error / shape_error for an inconsistent clip, io_error when the file cannot be written.
inline void write_csv(const std::filesystem::path& path, const clip& c) { write_file_atomic(path, to_csv_string(c)); }

/// @brief Parses CSV text (layout in the file comment) into a clip of skeleton `skel`.
/// @param source_name the file name used in error messages.
/// @param skel the skeleton; every joint must have its x, y, z columns (and px, py, pz when it has
/// position channels). Joints without position columns keep their OFFSET as position.
/// @throws format_error naming the file, 1-based line and column for an unknown, duplicate or missing
/// column, a value that is not a number or not finite, a row with the wrong number of fields, a bad
/// fps comment, or no data rows.
inline clip parse_csv(std::string_view text, std::string_view source_name, const skeleton& skel)
{
    skel.validate(std::string(source_name));
    if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);

    // Split into lines once (views into text), remembering 1-based numbers.
    struct line_view {
        std::string_view text;
        long number;
    };
    std::vector<line_view> lines;
    {
        std::size_t b = 0;
        long n = 1;
        while (b <= text.size()) {
            std::size_t e = text.find('\n', b);
            if (e == std::string_view::npos) e = text.size();
            const std::string_view l = detail::trim_blanks(text.substr(b, e - b));
            if (!l.empty()) lines.push_back({l, n});
            b = e + 1;
            ++n;
        }
    }

    double fps = 30.0;
    std::size_t i = 0;
    for (; i < lines.size() && lines[i].text.front() == '#'; ++i) {
        std::string_view c = detail::trim_blanks(lines[i].text.substr(1));
        if (c.substr(0, 4) != "fps=") continue;
        const std::string_view v = detail::trim_blanks(c.substr(4));
        if (detail::parse_number(v, fps) != detail::number_status::ok || !(fps > 0))
            detail::csv_fail(source_name, lines[i].number, "fps '" + std::string(v) + "' is not a positive number");
    }
    if (i >= lines.size()) detail::csv_fail(source_name, lines.empty() ? 1 : lines.back().number, "no header line (frame,<joint>_x,...)");

    // Header: column -> destination (angles or positions, joint, axis).
    const line_view header = lines[i++];
    std::vector<std::string_view> fields;
    detail::split_csv(header.text, fields);
    if (fields[0] != "frame")
        detail::csv_fail(source_name, header.number, "first column is '" + std::string(fields[0]) + "', expected 'frame'");
    const std::vector<std::string> names(fields.begin(), fields.end());
    std::unordered_map<std::string_view, std::size_t> by_name;
    for (std::size_t j = 0; j < skel.size(); ++j) by_name.emplace(skel.joints[j].name, j);
    struct column {
        bool position;
        std::size_t joint, axis;
    };
    std::vector<column> cols(fields.size());
    std::vector<long> seen(skel.size() * 6, -1);  // column index per (joint, slot): x y z px py pz
    for (std::size_t k = 1; k < fields.size(); ++k) {
        const std::string_view f = fields[k];
        const std::size_t us = f.rfind('_');
        if (us == std::string_view::npos || us == 0)
            detail::csv_fail(source_name, header.number, "unknown column '" + std::string(f) + "', expected <joint>_x, _y, _z, _px, _py or _pz");
        const std::string_view name = f.substr(0, us), suffix = f.substr(us + 1);
        const auto it = by_name.find(name);
        if (it == by_name.end())
            detail::csv_fail(source_name, header.number, "unknown column '" + std::string(f) + "': no joint '" + std::string(name) + "' in the skeleton");
        column col{};
        col.joint = it->second;
        if (suffix.size() == 2 && suffix[0] == 'p') {
            col.position = true;
            col.axis = static_cast<std::size_t>(suffix[1] - 'x');
        } else if (suffix.size() == 1) {
            col.axis = static_cast<std::size_t>(suffix[0] - 'x');
        } else {
            col.axis = 3;
        }
        if ((suffix.size() != 1 && suffix.size() != 2) || col.axis > 2 || (suffix.size() == 2 && suffix[0] != 'p'))
            detail::csv_fail(source_name, header.number, "unknown column '" + std::string(f) + "': suffix '" + std::string(suffix) +
                                    "' is not x, y, z, px, py or pz");
        if (col.position && !skel.joints[col.joint].has_position())
            detail::csv_fail(source_name, header.number, "column '" + std::string(f) + "': joint '" + std::string(name) +
                                    "' has no position channels in the skeleton");
        long& slot = seen[col.joint * 6 + (col.position ? 3 : 0) + col.axis];
        if (slot >= 0) detail::csv_fail(source_name, header.number, "duplicate column '" + std::string(f) + "'");
        slot = static_cast<long>(k);
        cols[k] = col;
    }
    for (std::size_t j = 0; j < skel.size(); ++j) {
        const std::size_t slots = skel.joints[j].has_position() ? 6 : 3;
        for (std::size_t s = 0; s < slots; ++s)
            if (seen[j * 6 + s] < 0)
                detail::csv_fail(source_name, header.number, "missing column '" + skel.joints[j].name + (s >= 3 ? "_p" : "_") + "xyz"[s % 3] + "'");
    }

    std::size_t rows = 0;
    for (std::size_t r = i; r < lines.size(); ++r) rows += lines[r].text.front() != '#';
    if (rows == 0) detail::csv_fail(source_name, header.number, "no data rows after the header");

    // The clip grows one frame per parsed row, never sized from the line count up front (a short line
    // must not reserve the J*3 values of a frame before it is found to be a row).
    clip out = clip::make(skel, 0, fps);
    const std::size_t J = skel.size();
    std::size_t frame = 0;
    for (; i < lines.size(); ++i) {
        if (lines[i].text.front() == '#') continue;
        detail::split_csv(lines[i].text, fields);
        if (fields.size() != cols.size())
            detail::csv_fail(source_name, lines[i].number, "row has " + std::to_string(fields.size()) + " fields, expected " +
                                      std::to_string(cols.size()) + " (as in the header)");
        out.angles.resize(out.angles.size() + J * 3, 0.0);
        for (std::size_t j = 0; j < J; ++j)
            for (std::size_t a = 0; a < 3; ++a) out.positions.push_back(skel.joints[j].offset[a]);
        out.frames = frame + 1;
        for (std::size_t k = 0; k < fields.size(); ++k) {
            double v = 0;
            const auto st = detail::parse_number(fields[k], v);
            if (st == detail::number_status::not_a_number)
                detail::csv_fail(source_name, lines[i].number, "column '" + names[k] + "': '" + std::string(fields[k]) + "' is not a number");
            if (st == detail::number_status::not_finite)
                detail::csv_fail(source_name, lines[i].number, "column '" + names[k] + "': value '" + std::string(fields[k]) + "' is not finite");
            if (k == 0) continue;
            const column& c = cols[k];
            (c.position ? out.positions : out.angles)[(frame * J + c.joint) * 3 + c.axis] = v;
        }
        ++frame;
    }
    return out;
}

/// @brief Reads a CSV motion file against a reference skeleton.
/// @throws io_error when the file cannot be read; format_error (file, line, column) when it is malformed.
inline clip read_csv(const std::filesystem::path& path, const skeleton& skel)
{
    return parse_csv(read_file(path), path.string(), skel);
}

}  // namespace handemo
