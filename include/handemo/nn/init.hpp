// PyTorch's default parameter initialisation, reproduced deterministically from a handemo::rng seed,
// for the StarGAN generator and discriminator of Sec. 3.3 of the hand paper (the paper trains the
// reference StarGAN, whose layers keep PyTorch's defaults). No paper equation lives here.
//
// The kind of each parameter is decided from its name and shape, as given by for_each_parameter:
//  - `<prefix>.weight` of rank >= 2 (Conv2d [out, in, kh, kw], ConvTranspose2d [in, out, kh, kw],
//    Linear [out, in]): kaiming_uniform(a = sqrt(5)), i.e. U(-b, b) with
//    b = gain * sqrt(3 / fan_in), gain = sqrt(2 / (1 + a^2)) = sqrt(1/3), hence b = 1 / sqrt(fan_in).
//    fan_in is computed as torch.nn.init._calculate_fan_in_and_fan_out does: shape[1] times the
//    product of shape[2:], for ConvTranspose2d too (where shape[1] is the output channel count).
//  - `<prefix>.bias` where `<prefix>.weight` has rank >= 2: U(-1/sqrt(fan_in), 1/sqrt(fan_in)) with
//    that weight's fan_in (Conv2d/ConvTranspose2d/Linear reset_parameters).
//  - `<prefix>.weight` of rank 1: InstanceNorm/BatchNorm affine scale, set to 1.
//  - `<prefix>.bias` whose weight has rank 1: affine shift, set to 0.
// Anything else (another suffix, a rank-0 weight, a bias with no weight beside it, a bias of rank
// != 1) is a value_error naming the parameter. Parameters are filled in enumeration order, element by
// element in memory order, one rng draw per element of the uniform kinds, so a seed fixes every value.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/nn/parameters.hpp>
#include <handemo/nn/rng.hpp>

#include <cmath>
#include <cstddef>
#include <map>
#include <span>
#include <string>
#include <string_view>

namespace handemo {

/// @brief How a parameter is initialised (see the rules in the header comment).
enum class init_kind {
    kaiming_uniform,  ///< weight of rank >= 2: U(+-1/sqrt(fan_in))
    fan_in_uniform,   ///< bias of a conv/linear: U(+-1/sqrt(fan_in of its weight))
    ones,             ///< rank-1 affine weight
    zeros,            ///< rank-1 affine bias
};

/// @brief fan_in of a weight as PyTorch computes it: shape[1] * prod(shape[2:]).
/// @throws value_error when the rank is below 2.
inline std::size_t pytorch_fan_in(std::span<const std::size_t> shape, std::string_view name = "weight")
{
    if (shape.size() < 2)
        throw value_error("init: " + std::string(name) + ": fan_in needs rank >= 2, shape is " + shape_string(shape));
    std::size_t f = shape[1];
    for (std::size_t i = 2; i < shape.size(); ++i) f *= shape[i];
    return f;
}

namespace detail {

inline std::string_view param_prefix(std::string_view name, std::string_view suffix) noexcept
{
    return name.substr(0, name.size() - suffix.size());
}

inline bool ends_with(std::string_view s, std::string_view suffix) noexcept
{
    return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

}  // namespace detail

/// @brief Initialises every parameter of `model` as PyTorch's default constructors would.
/// @param model any model with for_each_parameter (PyTorch names and layouts).
/// @param gen   the random source; advanced by one draw per element of every uniform-initialised tensor.
/// @throws value_error naming a parameter whose kind cannot be decided (see the header comment).
template <parameterised M>
void init_pytorch_default(M& model, rng& gen)
{
    // Pass 1: rank of each weight and the fan_in of the rank >= 2 ones, keyed by prefix.
    struct weight_info {
        std::size_t rank = 0, fan_in = 0;
    };
    std::map<std::string, weight_info, std::less<>> weights;
    model.for_each_parameter([&]<class T>(std::string_view name, std::span<T>, std::span<T>,
                                          std::span<const std::size_t> shape) {
        if (!detail::ends_with(name, ".weight") && name != "weight") return;
        if (shape.empty())
            throw value_error("init_pytorch_default: " + std::string(name) + ": rank-0 weight, expected rank >= 1");
        weight_info w{shape.size(), shape.size() >= 2 ? pytorch_fan_in(shape, name) : 0};
        weights[std::string(detail::param_prefix(name, "weight"))] = w;
    });
    // Pass 2: fill.
    model.for_each_parameter([&]<class T>(std::string_view name, std::span<T> value, std::span<T>,
                                          std::span<const std::size_t> shape) {
        double bound = 0.0;
        init_kind kind;
        if (detail::ends_with(name, "weight") && (name.size() == 6 || detail::ends_with(name, ".weight"))) {
            const auto& w = weights.find(detail::param_prefix(name, "weight"))->second;
            kind = w.rank >= 2 ? init_kind::kaiming_uniform : init_kind::ones;
            if (w.rank >= 2) bound = 1.0 / std::sqrt(static_cast<double>(w.fan_in));
        } else if (detail::ends_with(name, "bias") && (name.size() == 4 || detail::ends_with(name, ".bias"))) {
            if (shape.size() != 1)
                throw value_error("init_pytorch_default: " + std::string(name) + ": bias of shape " +
                                  shape_string(shape) + ", expected rank 1");
            const auto it = weights.find(detail::param_prefix(name, "bias"));
            if (it == weights.end())
                throw value_error("init_pytorch_default: " + std::string(name) + ": no " +
                                  std::string(detail::param_prefix(name, "bias")) +
                                  "weight beside it, cannot decide its fan_in");
            kind = it->second.rank >= 2 ? init_kind::fan_in_uniform : init_kind::zeros;
            if (it->second.rank >= 2) bound = 1.0 / std::sqrt(static_cast<double>(it->second.fan_in));
        } else {
            throw value_error("init_pytorch_default: " + std::string(name) +
                              ": unknown parameter kind, expected a name ending in .weight or .bias");
        }
        switch (kind) {
        case init_kind::ones:
            for (auto& v : value) v = T(1);
            break;
        case init_kind::zeros:
            for (auto& v : value) v = T(0);
            break;
        default:
            for (auto& v : value) v = static_cast<T>(gen.uniform(-bound, bound));
        }
    });
}

/// @brief Initialises `model` as PyTorch would, from a fresh rng seeded with `seed`.
template <parameterised M>
void init_pytorch_default(M& model, std::uint64_t seed)
{
    rng gen(seed);
    init_pytorch_default(model, gen);
}

}  // namespace handemo
