// The motion-image view of the hand paper's Figure 3: a K x J motion image (Eq. 3: keyframe i is row i,
// joint m is column m, the x/y/z angles are R/G/B, v = round(255 (p - p_min) / (p_max - p_min))) enlarged
// with nearest-neighbour sampling so its pattern can be read, with keyframe indices along the rows, joint
// names (rotated 90 degrees, reading upward) along the columns and thin grid lines between cells.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/image/rgb_image.hpp>
#include <handemo/render/canvas.hpp>
#include <handemo/render/font.hpp>

#include <algorithm>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace handemo {

/// @brief Enlarges a motion image (Figure 3) and labels its rows (keyframes) and columns (joints).
/// @param motion_img [K, J, 3] motion image: K keyframes (rows) by J joints (columns).
/// @param joint_names J names for the columns, or empty for column numbers.
/// @param scale pixels per cell side, 1..256 (labels are drawn when it is at least 8).
/// @return the labelled view: a keyframe axis on the left, rotated joint names below.
/// @throws shape_error when the image is empty or its buffer size is wrong, or the name count is neither
///         0 nor J; value_error when scale is out of range.
inline rgb_image render_motion_image(const rgb_image& motion_img, std::span<const std::string> joint_names = {},
                                     std::size_t scale = 24)
{
    const std::string fn = "render_motion_image";
    motion_img.validate(fn);
    if (motion_img.empty())
        throw shape_error(fn + ": image is " + std::to_string(motion_img.width) + "x" + std::to_string(motion_img.height) +
                          ", expected at least 1x1 (K keyframes x J joints)");
    if (!joint_names.empty() && joint_names.size() != motion_img.width)
        throw shape_error(fn + ": " + std::to_string(joint_names.size()) + " joint names for an image " +
                          std::to_string(motion_img.width) + " columns (joints) wide");
    if (scale < 1 || scale > 256) throw value_error(fn + ": scale " + std::to_string(scale) + " is not in 1..256");

    const long s = static_cast<long>(scale), K = static_cast<long>(motion_img.height), J = static_cast<long>(motion_img.width);
    const bool labels = scale >= 8;
    const int fs = scale >= 20 ? 2 : 1;  // font scale; a rotated glyph is 7 fs wide and must fit a column
    std::vector<std::string> names;
    for (long j = 0; j < J; ++j)
        names.push_back(joint_names.empty() ? std::to_string(j) : joint_names[static_cast<std::size_t>(j)]);
    long name_w = 0;
    for (auto& n : names) name_w = std::max(name_w, text_width(n, fs));
    const long left = labels ? text_width(std::to_string(std::max<long>(K - 1, 0)), fs) + text_height(fs) + 16 : 0;
    const long top = labels ? text_height(fs) + 10 : 0;
    const long bottom = labels ? name_w + 10 : 0;
    const long right = labels ? 6 : 0;
    const long W = left + J * s + right, H = top + K * s + bottom;
    canvas cv(static_cast<std::size_t>(W), static_cast<std::size_t>(H), {1, 1, 1});
    const color ink = color::rgb8(40, 40, 40), grid = color::rgb8(255, 255, 255);

    for (long r = 0; r < K; ++r)
        for (long c = 0; c < J; ++c) {
            const std::uint8_t* p = motion_img.at(static_cast<std::size_t>(r), static_cast<std::size_t>(c));
            cv.fill_rect(left + c * s, top + r * s, left + (c + 1) * s, top + (r + 1) * s, color::rgb8(p[0], p[1], p[2]));
        }
    if (scale >= 6) {  // one-pixel white grid between cells, half transparent so the pattern stays readable
        for (long r = 1; r < K; ++r) cv.fill_rect(left, top + r * s, left + J * s, top + r * s + 1, grid, 0.6f);
        for (long c = 1; c < J; ++c) cv.fill_rect(left + c * s, top, left + c * s + 1, top + K * s, grid, 0.6f);
    }
    if (labels) {
        draw_text(cv, left, 3, "keyframe \\ joint", ink, fs);
        // keyframe axis caption, rotated, then the indices right-aligned beside the rows
        const std::string cap = "keyframe";
        if (text_width(cap, fs) <= K * s)
            draw_text(cv, 3, top + (K * s + text_width(cap, fs)) / 2, cap, ink, fs, true);
        for (long r = 0; r < K; ++r) {
            const std::string t = std::to_string(r);
            draw_text(cv, left - 5 - text_width(t, fs), top + r * s + (s - text_height(fs)) / 2, t, ink, fs);
        }
        for (long c = 0; c < J; ++c)
            draw_text(cv, left + c * s + (s - text_height(fs)) / 2,
                      top + K * s + 6 + text_width(names[static_cast<std::size_t>(c)], fs), names[static_cast<std::size_t>(c)], ink, fs,
                      true);
    }
    return cv.to_image();
}

}  // namespace handemo
