// The definitions of <handemo/transfer.hpp>: include this in exactly one source file of a program that uses
// transfer_model (a second one fails to link with duplicate symbols; none, with undefined ones). It compiles the
// generator's kernels, checkpoint parsing and retargeting: the slow part the light header keeps out of other files.
#pragma once

#include <handemo/retarget/map_file.hpp>
#include <handemo/stargan/capture.hpp>
#include <handemo/transfer.hpp>

namespace handemo {

transfer_model::transfer_model(const std::filesystem::path& model) : model_(stargan::load_model(model)) {}

const std::vector<std::string>& transfer_model::emotions() const noexcept { return model_->info().domains; }

const std::string& transfer_model::neutral() const noexcept { return model_->info().neutral; }

transferred transfer_model::transfer(const clip& capture, std::string_view emotion, const transfer_settings& settings) const
{
    stargan::capture_options o;
    o.hand = settings.hand;
    o.detail = settings.detail;
    if (!settings.map.empty()) o.slots = retarget::read_map(settings.map, capture.skel);
    const auto source = settings.source.empty() ? std::optional<std::string_view>() : std::optional<std::string_view>(settings.source);
    auto r = stargan::transfer_capture(*model_, capture, emotion, source, o);
    return {std::move(r.motion), r.on_model.tempo, r.retargeted};
}

}  // namespace handemo
