// The light header for programs that load a model and transfer captures: clips, BVH files and transfer_model,
// nothing of training, evaluation, rendering or the circumplex. It declares transfer_model; its definitions are
// in <handemo/transfer_impl.hpp>, which exactly one source file of the program includes (the way single-header
// libraries split declaration and implementation), so every other file that includes this header compiles in a
// few seconds instead of compiling the kernels, checkpoint parsing and retargeting again.
//
//   // main.cpp                                   // handemo_impl.cpp, compiled once
//   #include <handemo/transfer.hpp>               #include <handemo/transfer_impl.hpp>
//
// Everything here is also in the umbrella <handemo.hpp>, whose stargan::load_model() and transfer_capture() are
// what transfer_model wraps.
#pragma once

#include <handemo/motion/bvh.hpp>
#include <handemo/motion/clip.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {

namespace stargan {
class emotion_model;
}

/// @brief Options of transfer_model::transfer().
struct transfer_settings {
    /// the capture's hand to transfer with a hand model: 'l', 'r', or 0 for its only hand
    char hand = 0;
    /// a joint map file (docs/retargeting.md) for a skeleton no naming convention describes; empty: by joint names
    std::filesystem::path map;
    /// the emotion the capture shows; empty: the model's neutral one
    std::string source;
    /// add the detail layer learned with the model (full-rate texture of the target emotion)
    bool detail = false;
};

/// @brief A transferred capture.
struct transferred {
    clip motion;              ///< on the capture's own skeleton; channels the model does not drive are the input's
    double tempo = 1.0;       ///< the duration factor applied
    bool retargeted = false;  ///< whether the capture went through a joint map (another skeleton than the model's)
};

/// @brief A loaded emotion model. Its const members are safe to call from any number of threads at once.
class transfer_model {
public:
    /// @brief Loads a model folder (`handemo train --out`, `handemo export --inference`) or its checkpoint file.
    /// @throws handemo::error (io_error, format_error, value_error) naming the file.
    explicit transfer_model(const std::filesystem::path& model);

    /// @brief The emotions the model transfers to (its domains, neutral among them).
    const std::vector<std::string>& emotions() const noexcept;
    /// @brief The model's neutral emotion.
    const std::string& neutral() const noexcept;

    /// @brief `capture` transferred to `emotion`: retargeted onto the model's skeleton when it is another one,
    /// transferred, and written back onto the capture's skeleton.
    /// @throws handemo::error: an unknown emotion, an unrecognised skeleton (naming what was tried), a body with
    /// two hands and no `hand`, a map file that does not fit.
    transferred transfer(const clip& capture, std::string_view emotion, const transfer_settings& settings = {}) const;

    /// @brief The whole model (declared in <handemo/stargan/transfer.hpp>) for everything else it can do.
    const stargan::emotion_model& model() const noexcept { return *model_; }

private:
    std::shared_ptr<const stargan::emotion_model> model_;
};

}  // namespace handemo
