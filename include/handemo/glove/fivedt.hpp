// The 5DT Data Glove Ultra over USB (a HID-class device; the wireless kit presents the same reports):
// vendor id 0x5d70; the product id's bit 0 is set on a left glove, bit 4 on the 5-sensor model (Data
// Glove 5 Ultra, else the 14-sensor Data Glove 14 Ultra), bits 1 and 2 name the wireless kit's port
// (0x02 port A, 0x06 port B). An input report is 64 bytes without a report id: 16 big-endian 16-bit
// values, a 12-bit flex reading (0..4095) in the first 14. The 14-sensor glove's order: per finger from
// the thumb, the near (knuckle) sensor, the far (middle joint) sensor and, except after the little finger,
// the abduction sensor between it and the next finger; the 5-sensor glove fills the near slots (values 0,
// 3, 6, 9, 12) with one sensor per finger. No device clock or counter: samples are timed on arrival.
// Into the solve: a near sensor is the MCP joint's flexion (thumb: MCP), a far sensor the PIP joint's
// (thumb: IP), the DIP joint follows PIP by the coupling; on the 5-sensor glove the one sensor drives MCP
// and PIP (a finger bends as a whole). An abduction sensor is the spread of the two fingers it sits
// between, read as the abduction of the outer one (thumb-index: the thumb's CMC toward the thumb,
// index-middle: the index, middle-ring: the ring, ring-little: the little finger), the middle finger
// staying at 0. The raw range depends on the glove: the nominal flat/fist readings are placeholders for
// `glove calibrate` (flat hand, then a fist); the abduction sensors keep their nominal spread.
#pragma once

#include <handemo/glove/profile.hpp>

#include <cstdint>
#include <string>

namespace handemo {

inline constexpr std::uint16_t fivedt_vendor_id = 0x5d70;

/// @brief The product id of a wired 5DT Data Glove Ultra. @throws value_error unless sensors is 5 or 14.
inline std::uint16_t fivedt_product_id(int sensors, hand_side hand)
{
    if (sensors != 5 && sensors != 14) throw value_error("5dt: the Data Glove Ultra has 5 or 14 sensors, not " + std::to_string(sensors));
    return static_cast<std::uint16_t>((sensors == 5 ? 0x10 : 0x00) | (hand == hand_side::left ? 0x01 : 0x00));
}

/// @brief The profile of a 5DT Data Glove Ultra (see the file comment). @throws value_error unless sensors is 5 or 14.
inline glove_profile fivedt_profile(int sensors = 14, hand_side hand = hand_side::right)
{
    glove_profile p;
    p.vendor_id = fivedt_vendor_id;
    p.product_id = fivedt_product_id(sensors, hand);
    p.name = "5dt-ultra-" + std::to_string(sensors) + "-" + std::string(to_string(hand));
    p.description = "5DT Data Glove " + std::to_string(sensors) + " Ultra, " + std::string(to_string(hand)) + " hand, USB HID";
    p.rate_hz = 75;
    glove_report_layout L;
    L.id = -1;
    L.size = 64;
    auto flex = [&](std::size_t value, const std::string& name, const std::string& bone, double fist_angle, axis ax = axis::x) {
        glove_field f;
        f.name = name, f.kind = field_kind::flex, f.bone = bone, f.offset = value * 2;
        f.type = value_type::u16, f.big_endian = true;
        f.range_min = 0, f.range_max = 4095, f.flat = 1000, f.fist = 3000, f.fist_angle = fist_angle, f.rotation_axis = ax;
        f.fist_calibrated = ax == axis::x;
        L.fields.push_back(f);
    };
    const std::string fingers[] = {"thumb", "index", "middle", "ring", "pinky"};
    for (std::size_t k = 0; k < 5; ++k) {
        const std::string& fn = fingers[k];
        const std::string near_bone = fn + (k == 0 ? "_intermediate" : "_proximal"), far_bone = fn + (k == 0 ? "_distal" : "_intermediate");
        if (sensors == 5) {
            flex(3 * k, fn, near_bone, k == 0 ? 60 : 90);
            if (k > 0) flex(3 * k, fn + "_far", far_bone, 110);
            else flex(3 * k, fn + "_far", far_bone, 80);
            continue;
        }
        flex(3 * k, fn + "_near", near_bone, k == 0 ? 60 : 90);
        flex(3 * k + 1, fn + "_far", far_bone, k == 0 ? 80 : 110);
        if (k < 4) {
            static const char* outer[] = {"thumb_proximal", "index_proximal", "ring_proximal", "pinky_proximal"};
            static const double spread[] = {-30, -20, 20, 20};
            flex(3 * k + 2, fn + "_" + fingers[k + 1] + "_abduction", outer[k], spread[k], axis::z);
        }
    }
    p.reports.push_back(std::move(L));
    p.index();
    return p;
}

}  // namespace handemo
