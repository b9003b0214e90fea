// A clip with its labels: the motion type (content), the emotion and the take it was captured as, and the file
// it came from. What the datasets load (stargan/dataset.hpp) and what the metrics and baselines are fitted on.
#pragma once

#include <handemo/motion/clip.hpp>

#include <filesystem>
#include <string>

namespace handemo {

/// @brief One labelled clip.
struct labelled_clip {
    std::filesystem::path path;
    std::string content;
    std::string emotion;
    std::string take;
    clip motion;
};

}  // namespace handemo
