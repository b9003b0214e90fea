// The circumplex subcommands `handemo rcm fit | analyse | eval` (Aristidou et al. 2017, Section 3) in one
// translation unit; built only with xtensor-blas (target handemo::rcm). The synthesis side adds `rcm
// stylise` (rcm/stylise.hpp) and `rcm path` (rcm/path.hpp); rcm/eval_ext.hpp adds `--rcm` to `handemo eval`.
#include "registry.hpp"

#include "rcm/common.hpp"
#include "rcm/fit.hpp"
#include "rcm/analyse.hpp"
#include "rcm/eval.hpp"
#include "rcm/stylise.hpp"
#include "rcm/path.hpp"
#include "rcm/eval_ext.hpp"

static handemo::cli::add_command reg_rcm{70, [](CLI::App& app) {
    auto* rcm = app.add_subcommand("rcm", "Continuous emotion on the circumplex (Aristidou et al. 2017): fit, analyse, eval, stylise, path");
    rcm->require_subcommand(1);
    handemo::cli::rcm_cmd::add_fit(*rcm);
    handemo::cli::rcm_cmd::add_analyse(*rcm);
    handemo::cli::rcm_cmd::add_eval(*rcm);
    handemo::cli::rcm_cmd::add_stylise(*rcm);
    handemo::cli::rcm_cmd::add_path(*rcm);
}};

static handemo::cli::add_eval_extension reg_rcm_eval{{handemo::cli::rcm_cmd::add_eval_ext_options, handemo::cli::rcm_cmd::make_eval_ext}};
