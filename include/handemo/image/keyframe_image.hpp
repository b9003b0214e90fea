// The motion image of the hand paper as a handemo::rgb_image (Section 3.3.1: "each frame of a motion is
// represented as a row of an image while each joint ... as a column"; Eq. 3 / Eq. 6 live in codec.hpp):
// keyframe_pixels [K, J, 3] <-> an image K pixels high and J pixels wide, R, G, B = x, y, z angles. It
// lives with image I/O because it includes <handemo/image.hpp> (stb, target handemo::image), so the motion
// module never pulls in stb. It bridges the two modules: <handemo/image.hpp> does not include it (the image
// module itself stays free of motion/); include it where both are used.
#pragma once

#include <handemo/image.hpp>
#include <handemo/motion/codec.hpp>

#include <cstddef>
#include <string>

namespace handemo {

/// @brief Keyframe pixels [K, J, 3] as an image of width J and height K (the layouts coincide).
template <std::size_t K>
rgb_image to_image(const keyframe_pixels<K>& px)
{
    rgb_image im;
    im.width = px.joints;
    im.height = px.count();
    im.pixels = px.values;
    im.validate("to_image");
    return im;
}

/// @brief Image of width J and height K back to keyframe pixels.
/// @param expected_joints J (e.g. angle_range::joints); @param expected_keyframes K (a static K must agree)
/// @param what names the image in errors (usually its file name)
/// @throws shape_error naming `what`, the size found and the size expected (width x height = joints x
///         keyframes).
template <std::size_t K>
keyframe_pixels<K> from_image(const rgb_image& im, std::size_t expected_joints, std::size_t expected_keyframes = K,
                              const std::string& what = "image")
{
    if (K != dynamic_keyframes && expected_keyframes != K)
        throw shape_error("from_image: " + what + ": " + std::to_string(expected_keyframes) +
                          " keyframes requested, the type holds " + std::to_string(K));
    im.validate("from_image: " + what);
    if (im.width != expected_joints || im.height != expected_keyframes)
        throw shape_error("from_image: " + what + ": image is " + std::to_string(im.width) + "x" +
                          std::to_string(im.height) + " (width x height), expected " + std::to_string(expected_joints) +
                          "x" + std::to_string(expected_keyframes) + " (joints x keyframes)");
    keyframe_pixels<K> px;
    px.count_ = expected_keyframes;
    px.joints = expected_joints;
    px.values = im.pixels;
    return px;
}

/// @brief Image to keyframe pixels with the shape recorded in a range file (joints x keyframes).
/// @throws value_error when the range does not record a shape; shape_error as from_image.
template <std::size_t K = dynamic_keyframes>
keyframe_pixels<K> from_image(const rgb_image& im, const angle_range& r, const std::string& what = "image")
{
    if (r.joints == 0 || r.keyframes == 0)
        throw value_error("from_image: " + what + ": the range records no image shape (joints " +
                          std::to_string(r.joints) + ", keyframes " + std::to_string(r.keyframes) + ")");
    return from_image<K>(im, r.joints, r.keyframes, what);
}

}  // namespace handemo
