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
#include <span>
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

/// @brief transfer_capture() of many captures to one `target` emotion, with G run on batches of ws.capacity()
/// captures (emotion_model::transfer_batch): out[i] is transfer_capture(model, in[i], target, source, options[i])
/// bit for bit. A capture that fails (a skeleton that cannot be retargeted, a clip transfer() refuses) does not stop
/// the others: its error is returned and out[i] is left as it was.
/// @return one string per capture: empty when out[i] holds its result, else the error that stopped it.
/// @throws value_error when options or out is shorter than in; value_error for an unknown target or source.
inline std::vector<std::string> transfer_capture_batch(const emotion_model& model, std::span<const clip> in, std::string_view target,
                                                       std::optional<std::string_view> source, std::span<const capture_options> options,
                                                       emotion_model::batch_workspace& ws, std::span<capture_result> out)
{
    if (options.size() < in.size() || out.size() < in.size())
        throw value_error("transfer: transfer_capture_batch of " + std::to_string(in.size()) + " captures with " +
                          std::to_string(options.size()) + " options into " + std::to_string(out.size()) + " results");
    model.domain(target);  // an unknown emotion stops here, before any capture is touched
    if (source) model.domain(*source);
    std::vector<std::string> errors(in.size());
    // 1. every capture onto the model's skeleton, as transfer_capture_with() does
    const skeleton ms = model.model_skeleton();
    std::vector<capture_result> r(in.size());
    std::vector<clip> on_model;
    std::vector<std::size_t> index;  // the capture of each clip of on_model
    for (std::size_t i = 0; i < in.size(); ++i) {
        try {
            const capture_options& o = options[i];
            if (in[i].skel.same_topology(ms) && !o.hand && !o.slots) {
                on_model.push_back(in[i]);
            } else {
                retarget::map_options mo;
                mo.hand = o.hand;
                mo.source_slots = o.slots;
                r[i].map = retarget::make_map(in[i].skel, ms, mo);
                on_model.push_back(retarget::retarget_clip(in[i], *r[i].map, o.reference.empty() ? typical_pose(model) : o.reference));
                r[i].retargeted = true;
            }
            index.push_back(i);
        } catch (const std::exception& e) {
            errors[i] = e.what();
        }
    }
    // 2. the transfers, G on batches; when one clip is refused, each clip alone, so that only it fails
    std::vector<transfer_result> t(on_model.size());
    std::vector<char> ok(on_model.size(), 1);
    try {
        model.transfer_batch(on_model, target, source, ws, t);
    } catch (const std::exception&) {
        auto one = model.make_workspace();
        for (std::size_t k = 0; k < on_model.size(); ++k) {
            try {
                model.transfer(on_model[k], target, source, one, t[k]);
            } catch (const std::exception& e) {
                errors[index[k]] = e.what();
                ok[k] = 0;
            }
        }
    }
    // 3. the detail layer and the way back onto each capture's skeleton
    for (std::size_t k = 0; k < on_model.size(); ++k) {
        if (!ok[k]) continue;
        const std::size_t i = index[k];
        try {
            if (options[i].detail)
                t[k].motion = source ? model.add_detail(t[k].motion, on_model[k], target, *source) : model.add_detail(t[k].motion, on_model[k], target);
            r[i].on_model = std::move(t[k]);
            r[i].motion = r[i].retargeted ? retarget::write_back(in[i], r[i].on_model.motion, *r[i].map) : r[i].on_model.motion;
            out[i] = std::move(r[i]);
        } catch (const std::exception& e) {
            errors[i] = e.what();
        }
    }
    return errors;
}

}  // namespace handemo::stargan
