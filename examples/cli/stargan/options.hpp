// The training hyper-parameters as command-line options, shared by `train`, `demo` and `eval`.
#pragma once

#include <handemo/stargan/train.hpp>

#include <CLI/CLI.hpp>

namespace handemo::cli {

/// @brief Adds every hyper-parameter of `t` to `sub`; `--lr` (stored in `lr`, negative when absent) sets both rates.
inline void add_train_options(CLI::App* sub, stargan::train_options& t, double& lr)
{
    sub->add_option("--threads", t.threads, "Worker threads (0: all cores)")->capture_default_str();
    sub->add_option("--lr", lr, "Learning rate of both G and D (overrides --g-lr and --d-lr)");
    sub->add_option("--g-lr", t.g_lr, "Learning rate of G")->capture_default_str();
    sub->add_option("--d-lr", t.d_lr, "Learning rate of D")->capture_default_str();
    sub->add_option("--lambda-cls", t.lambda_cls, "Weight of the domain classification loss")->capture_default_str();
    sub->add_option("--lambda-rec", t.lambda_rec, "Weight of the reconstruction loss")->capture_default_str();
    sub->add_option("--lambda-gp", t.lambda_gp, "Weight of the gradient penalty")->capture_default_str();
    sub->add_option("--n-critic", t.n_critic, "D iterations per G iteration")->capture_default_str();
    sub->add_option("--beta1", t.beta1, "Adam beta1")->capture_default_str();
    sub->add_option("--beta2", t.beta2, "Adam beta2")->capture_default_str();
    sub->add_option("--decay-start", t.decay_start, "Fraction of training after which the learning rate decays linearly to 0")
        ->capture_default_str();
}

/// @brief Applies `--lr` and validates.
inline void finish_train_options(stargan::train_options& t, double lr)
{
    if (lr >= 0) t.g_lr = t.d_lr = lr;
    t.validate();
}

}  // namespace handemo::cli
