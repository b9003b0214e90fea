// The one interface between handemo's networks and everything that treats their parameters as a
// list of named tensors (initialisation, Adam, safetensors checkpoints): a model exposes
// `for_each_parameter(f)` calling `f(name, value, grad, shape)` with PyTorch names and layouts, as the
// StarGAN generator and discriminator of Sec. 3.3 of the hand paper do. No paper equation lives here.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace handemo {
namespace detail {

/// A callback accepting any element type, used only to test the for_each_parameter concept.
struct parameter_probe {
    template <class T>
    void operator()(std::string_view, std::span<T>, std::span<T>, std::span<const std::size_t>) const noexcept
    {
    }
};

}  // namespace detail

/// @brief A model whose parameters can be enumerated as (name, value, grad, shape) in a fixed order.
template <class M>
concept parameterised = requires(M& m) { m.for_each_parameter(detail::parameter_probe{}); };

/// @brief Product of the extents of `shape` (1 for a scalar).
inline std::size_t shape_numel(std::span<const std::size_t> shape) noexcept
{
    std::size_t n = 1;
    for (std::size_t d : shape) n *= d;
    return n;
}

/// @brief Formats a shape as `[2, 3, 4]` for error messages.
inline std::string shape_string(std::span<const std::size_t> shape)
{
    std::string s = "[";
    for (std::size_t i = 0; i < shape.size(); ++i) {
        if (i) s += ", ";
        s += std::to_string(shape[i]);
    }
    return s + "]";
}

/// @brief Name, shape and element count of one parameter, as enumerated by for_each_parameter.
struct parameter_info {
    std::string name;
    std::vector<std::size_t> shape;
    std::size_t numel = 0;
};

/// @brief Lists the parameters of a model in enumeration order.
template <parameterised M>
std::vector<parameter_info> list_parameters(M& model)
{
    std::vector<parameter_info> out;
    model.for_each_parameter([&]<class T>(std::string_view name, std::span<T> value, std::span<T>,
                                          std::span<const std::size_t> shape) {
        out.push_back({std::string(name), std::vector<std::size_t>(shape.begin(), shape.end()), value.size()});
    });
    return out;
}

}  // namespace handemo
