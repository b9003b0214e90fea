// Methods and scores from outside the core evaluation, run inside the same leave-one-content-out folds and
// reported in the same tables: the hook through which eval/rcm.hpp adds the circumplex method of Aristidou
// et al. 2017 (target handemo::rcm, LAPACK) without the core protocol including it. An extension sees each
// fold's training clips before any input is transferred, adds output clips as extra method rows (scored with
// every metric of metrics.hpp like the built-in methods), may add its own score to every sample, and writes
// report sections of its own.
#pragma once

#include <handemo/eval/report.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/stargan/dataset.hpp>

#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace handemo::eval {

/// @brief What an extension may see of one fold.
struct fold_context {
    std::string held_out;                                ///< the held-out content
    std::string neutral;                                 ///< the neutral label (inputs are its clips)
    const std::vector<labelled_clip>* train = nullptr;  ///< the fold's training clips: the only ones to fit on
    std::vector<const labelled_clip*> test;     ///< the held-out clips (every emotion), for scoring only
    std::size_t fold_index = 0;
    std::FILE* progress_out = nullptr;
};

/// @brief A method (or score) added to the evaluation from outside its core; see eval_options::extensions.
class method_extension {
public:
    virtual ~method_extension() = default;
    /// @brief Lines (`key value`) added to the report's options block.
    virtual std::string options_text() const { return {}; }
    /// @brief Called once per fold before any input is transferred: fit on `f.train` only.
    virtual void begin_fold(const fold_context& f) = 0;
    /// @brief Output clips for one held-out neutral input and a target emotion, as (method name, clip); each is
    /// scored against the real target clip exactly as the built-in methods are. Empty when the extension has
    /// nothing for this pair (it should say why in its report section).
    virtual std::vector<std::pair<std::string, clip>> transfer(const labelled_clip& input, const std::string& target) = 0;
    /// @brief Adds the extension's own numbers to a sample of any method whose output clip is `out`.
    virtual void score(sample_record& s, const clip& out) { (void)s, (void)out; }
    /// @brief A circumplex point (valence, arousal) of a clip of the fold's held-out content whose ranks among that
    /// content's clips are the extension's analysis's (NaN when it has none): what the continuous control's Spearman
    /// correlations are taken on (eval/continuous.hpp).
    virtual std::pair<double, double> circumplex_rank_point(const clip& out)
    {
        (void)out;
        return {std::nan(""), std::nan("")};
    }
    /// @brief Called after each fold's samples are in `r`: add or replace the extension's report sections.
    virtual void end_fold(eval_result& r) { (void)r; }
};

}  // namespace handemo::eval
