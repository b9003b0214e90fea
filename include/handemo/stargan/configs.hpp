// Named StarGAN configurations and their run-time dispatch: the network sizes are compile-time
// (shapes live in the types), the CLI chooses one by name. Domain names are the emotion labels in
// label order; `neutral` is the domain transfers usually start from and tempo factors are relative to.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/stargan/model.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace handemo::stargan {

/// A small configuration for tests and quick experiments: the hand image, conv_dim 8, 1 residual block.
struct hand_tiny {
    static constexpr std::size_t joints = 23, keyframes = 9, domains = 5, conv_dim = 8, res_blocks = 1,
                                 d_repeat = 3, batch = 1;
};

/// @brief Run-time description of a named configuration.
struct config_info {
    std::string name;
    std::size_t joints, keyframes, domains, conv_dim, res_blocks, d_repeat;
    std::vector<std::string> domain_names;  ///< label order
    std::string neutral;                    ///< the neutral domain
};

/// The hand paper's emotions (Table 1) in label order.
inline std::vector<std::string> hand_domains() { return {"angry", "happy", "neutral", "sad", "fearful"}; }
/// The Bandai dataset-1 styles (`style_label.txt` order of the subset in ../shared/data/bandai).
inline std::vector<std::string> body_domains()
{
    return {"normal", "happy", "sad", "angry", "proud", "not-confident", "tired", "active"};
}

template <stargan_config C>
config_info make_info(std::string name, std::vector<std::string> domains, std::string neutral)
{
    if (domains.size() != C::domains)
        throw value_error("config " + name + ": " + std::to_string(domains.size()) + " domain names for " +
                          std::to_string(C::domains) + " domains");
    return {std::move(name), C::joints,    C::keyframes, C::domains,          C::conv_dim,
            C::res_blocks,   C::d_repeat,  std::move(domains), std::move(neutral)};
}

/// Names accepted by with_config().
inline std::vector<std::string> config_names() { return {"hand-embedded", "hand-paper", "body-embedded", "hand-micro", "hand-tiny"}; }

/// The configurations with_config() compiles, one bit each in config_names() order: hand-embedded 1, hand-paper 2,
/// body-embedded 4, hand-micro 8, hand-tiny 16. Every configuration with_config() meets costs the program the
/// compile time of its training, transfer and evaluation; a program that needs fewer (handemo's own test
/// programs) defines HANDEMO_CONFIG_MASK to the ones it uses, and a checkpoint of any other is then refused by
/// name. Default: all of them.
#ifndef HANDEMO_CONFIG_MASK
#define HANDEMO_CONFIG_MASK 31
#endif
inline constexpr unsigned compiled_configs = HANDEMO_CONFIG_MASK;
static_assert(compiled_configs != 0 && compiled_configs < 32, "HANDEMO_CONFIG_MASK: a non-empty subset of the 5 configuration bits");

/// The functions that choose a configuration by name at run time (stargan::load_model(), export_generator_header(),
/// eval::run_eval_named()) are templates on an unused, defaulted parameter, called as plain functions. A
/// non-template inline function would instantiate with_config()'s every branch (training, transfer and evaluation
/// for every configuration) in each translation unit that includes its header, whether it calls it or not; a
/// template is instantiated only where it is called.

/// @brief Calls `f.template operator()<Config>(info)` for the configuration called `name`.
/// @throws value_error listing the known names when `name` is unknown, and naming HANDEMO_CONFIG_MASK when it is
///         a configuration this program was compiled without.
template <class F>
decltype(auto) with_config(std::string_view name, F&& f)
{
    if constexpr ((compiled_configs & 1u) != 0) {
        if (name == "hand-embedded")
            return f.template operator()<hand_embedded>(make_info<hand_embedded>("hand-embedded", hand_domains(), "neutral"));
    }
    if constexpr ((compiled_configs & 2u) != 0) {
        if (name == "hand-paper")
            return f.template operator()<hand_paper>(make_info<hand_paper>("hand-paper", hand_domains(), "neutral"));
    }
    if constexpr ((compiled_configs & 4u) != 0) {
        if (name == "body-embedded")
            return f.template operator()<body_embedded>(make_info<body_embedded>("body-embedded", body_domains(), "normal"));
    }
    if constexpr ((compiled_configs & 8u) != 0) {
        if (name == "hand-micro")
            return f.template operator()<hand_micro>(make_info<hand_micro>("hand-micro", hand_domains(), "neutral"));
    }
    if constexpr ((compiled_configs & 16u) != 0) {
        if (name == "hand-tiny")
            return f.template operator()<hand_tiny>(make_info<hand_tiny>("hand-tiny", hand_domains(), "neutral"));
    }
    std::string known;
    const auto names = config_names();
    for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
    for (std::size_t i = 0; i < names.size(); ++i)
        if (names[i] == name)
            throw value_error("config: configuration '" + std::string(name) + "' is not compiled into this program (HANDEMO_CONFIG_MASK " +
                              std::to_string(compiled_configs) + " leaves out bit " + std::to_string(1u << i) + ")");
    throw value_error("config: unknown configuration '" + std::string(name) + "', expected one of " + known);
}

/// @brief Index of `emotion` in a list of domain names.
/// @param what prefix of the error message (who asks: a configuration, a model)
/// @throws value_error naming the unknown emotion and the known ones.
inline std::size_t domain_index(const std::vector<std::string>& names, std::string_view emotion, const std::string& what)
{
    for (std::size_t i = 0; i < names.size(); ++i)
        if (names[i] == emotion) return i;
    std::string known;
    for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
    throw value_error(what + ": unknown emotion '" + std::string(emotion) + "', expected one of " + known);
}

/// @brief Index of a domain name of a configuration.
/// @throws value_error naming the unknown emotion and the known ones.
inline std::size_t domain_index(const config_info& c, std::string_view emotion)
{
    return domain_index(c.domain_names, emotion, "config " + c.name);
}

}  // namespace handemo::stargan
