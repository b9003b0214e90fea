// Finite-difference gradient check (central differences, double precision) shared by the autodiff
// tests: the one thing worth copying from tiny-dnn's per-layer gradient_check. A case is a list of
// parameter vectors and a function that records a scalar loss on a tape from leaves over them.
#pragma once

#include <handemo/autodiff.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <string>
#include <vector>

namespace handemo::test {

/// One checked input: values, the gradient backward() accumulates, and whether it is checked.
struct gc_param {
    std::vector<double> value, grad;
    bool check = true;
};

/// Leaf var over parameter k (values and grads live in the gc_param).
template <class S>
autodiff::var<double, S> leaf(autodiff::tape<double>& t, std::vector<gc_param>& ps, std::size_t k)
{
    REQUIRE(ps[k].value.size() == S::size);
    return t.template parameter<S>(ps[k].value.data(), ps[k].grad.data());
}

/// Uniform values in [-a, a], kept at least `gap` away from 0 (away from relu/abs kinks).
inline gc_param random_param(std::size_t n, std::mt19937& rng, double a = 1.0, double gap = 0.05)
{
    std::uniform_real_distribution<double> u(gap, a);
    std::bernoulli_distribution sign(0.5);
    gc_param p;
    p.value.resize(n);
    for (auto& v : p.value) v = sign(rng) ? u(rng) : -u(rng);
    p.grad.assign(n, 0.0);
    return p;
}

/// Checks d loss / d every (or up to `max_per_param` random) element of every checked parameter
/// against (f(v + h) - f(v - h)) / 2h. `collect`, if set, runs after backward (see model_test). Returns the largest relative error seen.
/// Pass criterion per element: |a - n| <= rtol (|a| + |n|) + atol + 4 eps max(1, |f|) / h.
inline double gradcheck(std::vector<gc_param>& ps, const std::function<int(autodiff::tape<double>&)>& build,
                        double rtol = 1e-6, double atol = 1e-9, std::size_t max_per_param = 60, double h = 1e-5,
                        const std::function<void()>& collect = {})
{
    autodiff::tape<double> t(1 << 16);
    for (auto& p : ps) std::fill(p.grad.begin(), p.grad.end(), 0.0);
    const int loss = build(t);
    REQUIRE(t.at(loss).size == 1);
    t.backward(loss);
    const double loss_value = t.at(loss).value[0];
    if (collect) collect();  // copies gradients a model accumulated in its own buffers into ps
    auto eval = [&] {
        t.reset();
        const int l = build(t);
        return t.at(l).value[0];
    };
    // The rounding error of a central difference is about eps |f| / h: add it to the absolute tolerance.
    const double f0 = std::abs(loss_value);
    atol += 4 * 2.2e-16 * std::max(1.0, f0) / h;
    std::mt19937 rng(7);
    double worst = 0;
    for (std::size_t k = 0; k < ps.size(); ++k) {
        if (!ps[k].check) continue;
        std::vector<std::size_t> idx(ps[k].value.size());
        for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = i;
        if (idx.size() > max_per_param) {
            std::shuffle(idx.begin(), idx.end(), rng);
            idx.resize(max_per_param);
        }
        for (std::size_t i : idx) {
            const double v = ps[k].value[i];
            ps[k].value[i] = v + h;
            const double fp = eval();
            ps[k].value[i] = v - h;
            const double fm = eval();
            ps[k].value[i] = v;
            const double num = (fp - fm) / (2 * h), ana = ps[k].grad[i];
            const double err = std::abs(num - ana), scale = std::abs(num) + std::abs(ana);
            worst = std::max(worst, scale > 0 ? err / scale : 0.0);
            if (!(err <= rtol * scale + atol)) {
                INFO("param " << k << " element " << i << ": analytic " << ana << " numeric " << num);
                CHECK(err <= rtol * scale + atol);
            }
        }
    }
    return worst;
}

}  // namespace handemo::test
