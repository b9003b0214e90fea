// The Adam optimiser exactly as torch.optim.Adam (PyTorch 1.13, single-tensor path, weight decay 0,
// amsgrad off) and the learning-rate schedule used to train the StarGAN of Sec. 3.3 of the hand paper
// (constant, then linear decay to 0, as the reference StarGAN trains). For each element, at step t:
//     m <- beta1 m + (1 - beta1) g
//     v <- beta2 v + (1 - beta2) g^2
//     p <- p - (lr / (1 - beta1^t)) * m / (sqrt(v) / sqrt(1 - beta2^t) + eps)
// which is p -= lr * m_hat / (sqrt(v_hat) + eps) evaluated in PyTorch's order of operations (the bias
// corrections in double, the element arithmetic in the parameter's type). The state (m, v for every
// element, one step count per tensor) is stored flat, allocated once at construction and exposed as
// spans so that a checkpoint can save and restore it.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/core/thread_pool.hpp>
#include <handemo/nn/parameters.hpp>

#include <xsimd/xsimd.hpp>

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace handemo {

/// @brief Hyper-parameters of Adam (the StarGAN defaults: betas 0.5, 0.999).
struct adam_options {
    double beta1 = 0.5;
    double beta2 = 0.999;
    double eps = 1e-8;
};

/// @brief Learning rate constant at `base`, then decaying linearly to 0 over the last part of training.
///
/// lr(step) = base for step < s0 = floor(decay_start * total_steps), and
/// base * (total_steps - step) / (total_steps - s0) for s0 <= step <= total_steps (0 at the end and
/// beyond). `step` counts from 0 (the step about to be taken).
struct lr_schedule {
    double base = 1e-4;
    std::int64_t total_steps = 1;
    double decay_start = 0.5;  ///< fraction of total_steps after which the decay begins, in [0, 1]

    /// @throws value_error when base < 0, total_steps < 1 or decay_start outside [0, 1].
    void validate() const
    {
        if (!(base >= 0.0) || !std::isfinite(base))
            throw value_error("lr_schedule: base " + std::to_string(base) + " is not a finite value >= 0");
        if (total_steps < 1)
            throw value_error("lr_schedule: total_steps " + std::to_string(total_steps) + " is not >= 1");
        if (!(decay_start >= 0.0 && decay_start <= 1.0))
            throw value_error("lr_schedule: decay_start " + std::to_string(decay_start) + " is not in [0, 1]");
    }

    /// @brief First step of the decay, floor(decay_start * total_steps).
    std::int64_t decay_begin() const noexcept
    {
        return static_cast<std::int64_t>(std::floor(decay_start * static_cast<double>(total_steps)));
    }

    /// @brief Learning rate for the (0-based) step `step`.
    double operator()(std::int64_t step) const noexcept
    {
        const std::int64_t s0 = decay_begin();
        if (step < s0) return base;
        if (step >= total_steps) return 0.0;
        return base * static_cast<double>(total_steps - step) / static_cast<double>(total_steps - s0);
    }
};

/// @brief Adam over a fixed list of parameter tensors, state stored flat.
/// @tparam T element type of the parameters (float or double).
template <std::floating_point T>
class adam {
public:
    using value_type = T;

    /// @brief Optimiser for tensors of the given element counts (no names checked).
    explicit adam(std::span<const std::size_t> sizes, adam_options opt = {}) : opt_(opt)
    {
        check_options();
        for (std::size_t n : sizes) add_slot("", n);
        finish();
    }

    /// @brief Optimiser for every parameter of `model`, in enumeration order; remembers the names.
    template <parameterised M>
    explicit adam(M& model, adam_options opt = {}) : opt_(opt)
    {
        check_options();
        model.for_each_parameter([&]<class U>(std::string_view name, std::span<U> value, std::span<U>,
                                              std::span<const std::size_t>) {
            static_assert(std::same_as<U, T>, "adam<T>: model parameter type differs from the optimiser's T");
            add_slot(name, value.size());
        });
        finish();
    }

    /// @brief One Adam step on every parameter of `model` with its current gradients.
    /// @param lr learning rate of this step (e.g. schedule(step)).
    /// @param pool splits the elements of long tensors over its threads (element-wise: the same result).
    /// @throws shape_error when the model's parameter list differs from the one at construction
    ///         (name or element count), naming the parameter.
    template <parameterised M>
    void step(M& model, double lr, thread_pool* pool = nullptr)
    {
        std::size_t i = 0;
        model.for_each_parameter([&]<class U>(std::string_view name, std::span<U> value, std::span<U> grad,
                                              std::span<const std::size_t>) {
            static_assert(std::same_as<U, T>, "adam<T>: model parameter type differs from the optimiser's T");
            if (i >= names_.size() || names_[i] != name || offsets_[i + 1] - offsets_[i] != value.size())
                throw shape_error("adam::step: parameter " + std::to_string(i) + " is " + std::string(name) +
                                  " with " + std::to_string(value.size()) + " elements, expected " +
                                  (i < names_.size() ? names_[i] + " with " +
                                                           std::to_string(offsets_[i + 1] - offsets_[i]) + " elements"
                                                     : std::string("no more parameters")));
            step_tensor(i, value, grad, lr, pool);
            ++i;
        });
        if (i != names_.size())
            throw shape_error("adam::step: model has " + std::to_string(i) + " parameters, expected " +
                              std::to_string(names_.size()));
    }

    /// @brief One Adam step on tensor `index` (value and grad of its registered size).
    /// @throws shape_error when the index or the sizes are wrong.
    void step_tensor(std::size_t index, std::span<T> value, std::span<const T> grad, double lr, thread_pool* pool = nullptr)
    {
        if (index >= steps_.size())
            throw shape_error("adam::step_tensor: index " + std::to_string(index) + " is not below " +
                              std::to_string(steps_.size()));
        const std::size_t n = offsets_[index + 1] - offsets_[index];
        if (value.size() != n || grad.size() != n)
            throw shape_error("adam::step_tensor: tensor " + std::to_string(index) + " has value " +
                              std::to_string(value.size()) + " and grad " + std::to_string(grad.size()) +
                              " elements, expected " + std::to_string(n));
        const std::int64_t t = ++steps_[index];
        const double bc1 = 1.0 - std::pow(opt_.beta1, static_cast<double>(t));
        const double bc2 = 1.0 - std::pow(opt_.beta2, static_cast<double>(t));
        T* m = m_.data() + offsets_[index];
        T* v = v_.data() + offsets_[index];
        auto run = [&](std::size_t lo, std::size_t hi) {
            update(value.data() + lo, grad.data() + lo, m + lo, v + lo, hi - lo, static_cast<T>(opt_.beta1),
                   static_cast<T>(1.0 - opt_.beta1), static_cast<T>(opt_.beta2), static_cast<T>(1.0 - opt_.beta2),
                   static_cast<T>(std::sqrt(bc2)), static_cast<T>(opt_.eps), static_cast<T>(-(lr / bc1)));
        };
        if (pool) parallel_blocks(*pool, n, run);
        else run(0, n);
    }

    /// @brief First moments of every element, tensors concatenated in registration order.
    std::span<T> m() noexcept { return m_; }
    std::span<const T> m() const noexcept { return m_; }
    /// @brief Second moments, same layout as m().
    std::span<T> v() noexcept { return v_; }
    std::span<const T> v() const noexcept { return v_; }
    /// @brief Number of steps taken, one per tensor (as torch keeps `state['step']` per parameter).
    std::span<std::int64_t> steps() noexcept { return steps_; }
    std::span<const std::int64_t> steps() const noexcept { return steps_; }
    /// @brief Offset of tensor i's first element in m() and v(); offsets()[tensor_count()] == m().size().
    std::span<const std::size_t> offsets() const noexcept { return offsets_; }
    /// @brief Names given at construction from a model (empty strings for the sizes constructor).
    std::span<const std::string> names() const noexcept { return names_; }
    std::size_t tensor_count() const noexcept { return steps_.size(); }
    const adam_options& options() const noexcept { return opt_; }

    /// @brief Forgets all state (moments 0, steps 0), as a fresh torch.optim.Adam.
    void reset() noexcept
    {
        std::fill(m_.begin(), m_.end(), T(0));
        std::fill(v_.begin(), v_.end(), T(0));
        std::fill(steps_.begin(), steps_.end(), 0);
    }

private:
    void check_options() const
    {
        if (!(opt_.beta1 >= 0.0 && opt_.beta1 < 1.0))
            throw value_error("adam: beta1 " + std::to_string(opt_.beta1) + " is not in [0, 1)");
        if (!(opt_.beta2 >= 0.0 && opt_.beta2 < 1.0))
            throw value_error("adam: beta2 " + std::to_string(opt_.beta2) + " is not in [0, 1)");
        if (!(opt_.eps >= 0.0)) throw value_error("adam: eps " + std::to_string(opt_.eps) + " is not >= 0");
    }
    void add_slot(std::string_view name, std::size_t n)
    {
        if (offsets_.empty()) offsets_.push_back(0);
        names_.emplace_back(name);
        offsets_.push_back(offsets_.back() + n);
    }
    void finish()
    {
        if (offsets_.empty()) offsets_.push_back(0);
        m_.assign(offsets_.back(), T(0));
        v_.assign(offsets_.back(), T(0));
        steps_.assign(names_.size(), 0);
    }

    // Element loop in PyTorch's operation order:
    //   m = m*b1 + g*(1-b1); v = v*b2 + (g*g)*(1-b2); p += (neg_step * m) / (sqrt(v)/sqrt_bc2 + eps)  (addcdiv)
    static void update(T* __restrict p, const T* __restrict g, T* __restrict m, T* __restrict v, std::size_t n,
                       T b1, T omb1, T b2, T omb2, T sqrt_bc2, T eps, T neg_step) noexcept
    {
        std::size_t nv = 0;  // elements done by the SIMD loop (none on a target xsimd has no instruction set for)
        if constexpr (!std::is_same_v<xsimd::default_arch, xsimd::unavailable>) {
            using batch = xsimd::batch<T>;
            constexpr std::size_t w = batch::size;
            nv = n - n % w;
            const batch vb1(b1), vomb1(omb1), vb2(b2), vomb2(omb2), vs(sqrt_bc2), ve(eps), vstep(neg_step);
            for (std::size_t i = 0; i < nv; i += w) {
                const batch gi = batch::load_unaligned(g + i);
                const batch mi = batch::load_unaligned(m + i) * vb1 + gi * vomb1;
                const batch vi = batch::load_unaligned(v + i) * vb2 + (gi * gi) * vomb2;
                const batch pi = batch::load_unaligned(p + i) + (vstep * mi) / (xsimd::sqrt(vi) / vs + ve);
                mi.store_unaligned(m + i);
                vi.store_unaligned(v + i);
                pi.store_unaligned(p + i);
            }
        }
        for (std::size_t i = nv; i < n; ++i) {
            const T gi = g[i];
            m[i] = m[i] * b1 + gi * omb1;
            v[i] = v[i] * b2 + (gi * gi) * omb2;
            p[i] = p[i] + (neg_step * m[i]) / (std::sqrt(v[i]) / sqrt_bc2 + eps);
        }
    }

    adam_options opt_;
    std::vector<std::string> names_;
    std::vector<std::size_t> offsets_;
    std::vector<T> m_, v_;
    std::vector<std::int64_t> steps_;
};

}  // namespace handemo
