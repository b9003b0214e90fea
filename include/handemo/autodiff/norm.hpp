// Instance normalisation op of handemo's autodiff tape, as PyTorch InstanceNorm2d(affine=True) in
// training mode: per-sample, per-channel statistics over space, biased variance, eps 1e-5. It follows
// every convolution of the StarGAN generator (hand paper Sec. 3.3, Fig. 3). First-order backward only
// (the WGAN-GP penalty differentiates D twice, and D has no normalisation).
#pragma once

#include <handemo/autodiff/tape.hpp>
#include <handemo/kernels/norm.hpp>

#include <cmath>

namespace handemo::autodiff {
namespace detail {

// For each (n, c) over its M = H W values: mu = mean x, var = mean (x - mu)^2, r = 1 / sqrt(var + eps),
// xh = (x - mu) r, y = gamma[c] xh + beta[c].
// d/dbeta[c] = sum_{n,m} g;   d/dgamma[c] = sum_{n,m} g xh;
// d/dx = gamma[c] r (g - mean_m g - xh mean_m (g xh))
// The record holds the layout [N, C, M] and eps; aux holds (mu, r) per (n, c).
template <class T>
struct instance_norm_params {
    int batch;
    int channels;
    int spatial;  ///< M = H W
    T eps;
};
template <class T>
void instance_norm_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const auto prm = n.template params<instance_norm_params<T>>();
    const int N = prm.batch, C = prm.channels, M = prm.spatial;
    const T* x = t.at(n.in[0]).value;
    const T* gamma = t.at(n.in[1]).value;
    T* gx = t.adj(n.in[0]);
    T* gg = t.adj(n.in[1]);
    T* gb = t.adj(n.in[2]);
    for (int b = 0; b < N; ++b)
        for (int c = 0; c < C; ++c) {
            const std::size_t o = (std::size_t(b) * C + c) * M;
            const T mu = n.aux[2 * (b * C + c)], r = n.aux[2 * (b * C + c) + 1];
            const T* g = n.adjoint + o;
            double sg = 0, sgx = 0;  // statistics accumulate in double (float sums lose digits here)
            for (int m = 0; m < M; ++m) {
                sg += g[m];
                sgx += double(g[m]) * ((x[o + m] - mu) * r);
            }
            if (gb) gb[c] += T(sg);
            if (gg) gg[c] += T(sgx);
            if (gx) {
                const T k = gamma[c] * r, mg = T(sg / M), mgx = T(sgx / M);
                for (int m = 0; m < M; ++m) gx[o + m] += k * (g[m] - mg - (x[o + m] - mu) * r * mgx);
            }
        }
}
template <class T>
int instance_norm_raw(tape<T>& t, int x, int gamma, int beta, int N, int C, int M, T eps)
{
    const int id = t.make("instance_norm", std::size_t(N) * C * M, {x, gamma, beta}, &instance_norm_backward<T>,
                          nullptr, instance_norm_params<T>{N, C, M, eps});
    T* aux = t.alloc(std::size_t(2) * N * C);
    node<T>& n = t.at(id);
    n.aux = aux;
    const T *xv = t.at(x).value, *gv = t.at(gamma).value, *bv = t.at(beta).value;
    for (int b = 0; b < N; ++b)
        for (int c = 0; c < C; ++c) {
            const std::size_t o = (std::size_t(b) * C + c) * M;
            double mud = 0, var = 0;  // two-pass statistics, accumulated in double
            kernels::channel_moments(xv + o, M, mud, var);
            const T mu = T(mud), r = T(1.0 / std::sqrt(var + double(eps)));
            n.aux[2 * (b * C + c)] = mu;
            n.aux[2 * (b * C + c) + 1] = r;
            const T k = gv[c] * r;  // k (x - mu) + beta: no cancellation between k x and k mu
            kernels::scale_shift(xv + o, M, k, mu, bv[c], false, n.value + o);
        }
    return id;
}

}  // namespace detail

/// @brief InstanceNorm2d(affine): x [N, C, H, W], gamma [C], beta [C] -> [N, C, H, W].
template <class T, std::size_t N, std::size_t C, std::size_t H, std::size_t W, std::size_t C1, std::size_t C2>
var<T, shape<N, C, H, W>> instance_norm(const var<T, shape<N, C, H, W>>& x, const var<T, shape<C1>>& gamma,
                                        const var<T, shape<C2>>& beta, T eps = T(1e-5))
{
    require_same_shape<"instance_norm (channels of x and gamma)", shape<C>, shape<C1>>();
    require_same_shape<"instance_norm (channels of x and beta)", shape<C>, shape<C2>>();
    return {x.t, detail::instance_norm_raw(*x.t, x.id, gamma.id, beta.id, int(N), int(C), int(H * W), eps)};
}

}  // namespace handemo::autodiff
