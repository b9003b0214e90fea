// `handemo decode IN.bmp --like REF.bvh --range RANGE.json --out OUT.bvh [--frames N] [--interp M]`: the
// way back from a motion image (Section 3.4): pixels -> angles by Eq. 6, then a full-rate clip by
// interpolating the keyframes (Catmull-Rom by default, handemo/motion/keyframes.hpp) on REF's skeleton,
// at REF's frame rate, with REF's frame count unless --frames is given. Root translation is not encoded
// in the image (the paper removes it) so the output keeps rest offsets. Prints the keyframe difference
// to REF (at most (p_max - p_min) / 510 when IN is REF's own image).
#pragma once

#include "../registry.hpp"

#include <handemo/image.hpp>
#include <handemo/motion.hpp>
#include <handemo/image/keyframe_image.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

namespace handemo::cli::decode_cmd {

struct decode_options {
    std::string in, like, range, out, interp = "catmull-rom";
    std::size_t frames = 0;
};

handemo::interpolation parse_interp(const std::string& s)
{
    if (s == "catmull-rom") return handemo::interpolation::catmull_rom;
    if (s == "natural") return handemo::interpolation::natural_spline;
    if (s == "linear") return handemo::interpolation::linear;
    throw handemo::value_error("decode: --interp '" + s + "' is not catmull-rom, natural or linear");
}

void run_decode(const decode_options& o)
{
    const handemo::interpolation method = parse_interp(o.interp);
    const handemo::angle_range r = handemo::load_range(o.range);
    const handemo::clip ref = handemo::read_bvh(o.like);
    if (r.joints && r.joints != ref.skel.size())
        throw handemo::shape_error("decode: " + o.like + " has " + std::to_string(ref.skel.size()) + " joints, " +
                                   o.range + " is for " + std::to_string(r.joints));
    const handemo::rgb_image im = handemo::read_image(o.in);
    const auto px = handemo::from_image<handemo::dynamic_keyframes>(im, r, o.in);
    const auto kf = handemo::decode(px, r);
    const std::size_t frames = o.frames ? o.frames : ref.frames;
    if (frames < 2) throw handemo::value_error("decode: --frames " + std::to_string(frames) + " is below 2");
    handemo::clip out = handemo::reconstruct(kf, ref.skel, frames, ref.fps, {}, method);
    // the image holds rotations only: position channels (a body's root translation) come from the reference,
    // stretched in time to the output length, as transfer does
    out.positions = handemo::stretch_positions(ref, frames);
    handemo::write_bvh(o.out, out);
    std::cout << "wrote " << o.out << " (" << frames << " frames at " << ref.fps << " fps, " << kf.joints << " joints, "
              << kf.count() << " keyframes)\n";
    if (ref.frames >= 2) {
        const auto kr = handemo::extract_keyframes<handemo::dynamic_keyframes>(ref, kf.count());
        double worst = 0;
        for (std::size_t i = 0; i < kr.angles.size(); ++i)
            worst = std::max(worst, std::abs(handemo::wrap_angle_deg(kr.angles[i] - kf.angles[i])));
        std::cout << "decode: max keyframe difference to " << o.like << ": " << worst
                  << " deg (codec bound (p_max-p_min)/510 = " << r.max_roundtrip_error() << " deg)\n";
    }
}

}  // namespace handemo::cli::decode_cmd

static handemo::cli::add_command reg_decode{30, [](CLI::App& app) {
    using namespace handemo::cli::decode_cmd;
    auto* sub = app.add_subcommand("decode", "Decode a motion image (Eq. 6) into a BVH clip on a reference skeleton");
    auto o = std::make_shared<decode_options>();
    sub->add_option("input", o->in, "Motion image (.bmp or .png)")->required();
    sub->add_option("--like", o->like, "Reference BVH: skeleton, frame rate and default frame count")->required();
    sub->add_option("--range", o->range, "range.json written by `handemo encode`")->required();
    sub->add_option("--out", o->out, "Output .bvh")->required();
    sub->add_option("--frames", o->frames, "Output frame count (default: the reference's)");
    sub->add_option("--interp", o->interp, "Keyframe interpolation: catmull-rom (default), natural, linear");
    sub->callback([o] { run_decode(*o); });
}};
