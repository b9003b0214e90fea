// Emotion transfer of a user's own capture, whatever its skeleton: the capture is retargeted onto the model's
// skeleton (retarget/, by joint-name convention or a map file; one hand picked out of a body and mirrored
// onto a right-hand model as needed), transferred there (transfer.hpp), and written back onto the capture's own
// skeleton, where only the driven joints' rotation channels change and every other channel is the capture's,
// resampled in time when the emotion changes the tempo.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/retarget.hpp>
#include <handemo/stargan/transfer.hpp>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::stargan {

/// @brief How a capture reaches the model (see transfer_capture()).
struct capture_options {
    /// the capture's hand to transfer with a hand model: 'l', 'r' or 0 (its only hand)
    char hand = 0;
    /// slots of the capture from a map file (retarget::read_map); default: detected from the joint names
    std::optional<retarget::binding> slots;
    /// add the detail layer (emotion_model::add_detail) on the model's skeleton before writing back
    bool detail = false;
    /// [J*3] angles on the model's skeleton whose Euler branches the capture's first frame takes on the model
    /// (a joint near gimbal lock has two); default: typical_pose(), the branches most of the training data uses
    std::vector<double> reference;
};

/// @brief A transfer of a capture: the result on the capture's skeleton and how it got there.
struct capture_result {
    clip motion;                 ///< on the capture's own skeleton
    transfer_result on_model;    ///< the transfer on the model's skeleton (motion, image, tempo, ...)
    bool retargeted = false;     ///< false: the capture was already on the model's skeleton
    std::optional<retarget::retarget_map> map;  ///< the correspondence used, when retargeted
};

/// @brief The model's typical pose, [J*3] angles: the centre of each channel's range (per-channel ranges), else
/// empty. A capture retargeted onto the model takes the Euler branch nearest it, the branch of the training data.
inline std::vector<double> typical_pose(const emotion_model& model)
{
    const auto& r = model.info().range;
    if (!r.per_channel() || r.center.size() != model.joints() * 3) return {};
    return r.center;
}

/// @brief A capture through `run` (clip on the model's skeleton -> transfer_result): a capture on the model's own
/// skeleton (same joint names and parents) with no hand or map asked for goes to `run` directly; any other is
/// retargeted there and written back. transfer_capture() and the continuous control's share it.
/// @throws what `run` and retarget::make_map() throw (unrecognised skeletons, two hands and no choice,
/// degenerate rest poses), naming the capture.
template <class Run>
capture_result transfer_capture_with(const emotion_model& model, const clip& in, const capture_options& o, Run&& run)
{
    capture_result r;
    const skeleton ms = model.model_skeleton();
    if (in.skel.same_topology(ms) && !o.hand && !o.slots) {
        r.on_model = run(in);
        r.motion = r.on_model.motion;
        return r;
    }
    retarget::map_options mo;
    mo.hand = o.hand;
    mo.source_slots = o.slots;
    r.map = retarget::make_map(in.skel, ms, mo);
    const clip on_model = retarget::retarget_clip(in, *r.map, o.reference.empty() ? typical_pose(model) : o.reference);
    r.on_model = run(on_model);
    r.motion = retarget::write_back(in, r.on_model.motion, *r.map);
    r.retargeted = true;
    return r;
}

/// @brief Transfers `in` to `target` emotion (transfer_capture_with() of emotion_model::transfer(), plus the
/// detail layer when asked for).
/// @throws what emotion_model::transfer() and retarget::make_map() throw (unrecognised skeletons, two hands
/// and no choice, degenerate rest poses), naming the capture.
inline capture_result transfer_capture(const emotion_model& model, const clip& in, std::string_view target,
                                       std::optional<std::string_view> source = {}, const capture_options& o = {})
{
    return transfer_capture_with(model, in, o, [&](const clip& c) {
        auto t = source ? model.transfer(c, target, *source) : model.transfer(c, target);
        if (o.detail) t.motion = source ? model.add_detail(t.motion, c, target, *source) : model.add_detail(t.motion, c, target);
        return t;
    });
}

}  // namespace handemo::stargan
