// A tiny stand-in model with for_each_parameter (PyTorch names and layouts) for the nn tests that do
// not need the real StarGAN networks: a Conv2d with bias, an InstanceNorm affine pair, a
// ConvTranspose2d without bias and a Linear-like head.
#pragma once

#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace handemo::test {

template <class T>
struct tiny_model {
    struct param {
        std::string name;
        std::vector<std::size_t> shape;
        std::vector<T> value, grad;
    };
    std::vector<param> params;

    tiny_model()
    {
        add("main.0.weight", {4, 3, 3, 3});   // Conv2d(3, 4, 3): fan_in 27
        add("main.0.bias", {4});
        add("main.1.weight", {4});            // InstanceNorm2d(4, affine=True)
        add("main.1.bias", {4});
        add("main.3.weight", {4, 2, 4, 4});   // ConvTranspose2d(4, 2, 4): fan_in 2*16 = 32
        add("head.weight", {5, 10});          // Linear(10, 5): fan_in 10
        add("head.bias", {5});
    }
    void add(std::string name, std::vector<std::size_t> shape)
    {
        std::size_t n = 1;
        for (auto d : shape) n *= d;
        params.push_back({std::move(name), std::move(shape), std::vector<T>(n, T(0)), std::vector<T>(n, T(0))});
    }
    template <class F>
    void for_each_parameter(F&& f)
    {
        for (auto& p : params)
            f(std::string_view(p.name), std::span<T>(p.value), std::span<T>(p.grad),
              std::span<const std::size_t>(p.shape));
    }
    param& get(std::string_view name)
    {
        for (auto& p : params)
            if (p.name == name) return p;
        throw std::runtime_error("no param");
    }
};

}  // namespace handemo::test
