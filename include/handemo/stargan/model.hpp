// The StarGAN generator and discriminator of the hand paper (Chan, Irimia, Ho 2020, Sec. 3.3, Fig. 3),
// laid out exactly as the official StarGAN (Choi et al. 2018, yunjey/stargan model.py) and handemo's
// reference_stargan.py, with the same PyTorch parameter names and layouts, for motion images: the
// K x J x 3 image of Eq. 3 (K keyframes, J joints, RGB = the three Euler angles) zero-padded at the
// bottom/right to H x W. G: conv7 -> IN -> ReLU -> 2 x [conv4 s2 -> IN -> ReLU] -> residual blocks ->
// 2 x [convT4 s2 -> IN -> ReLU] -> conv7 -> tanh, target label tiled as C extra input channels, no
// biases. D: d_repeat x [conv4 s2 (bias) -> LeakyReLU(0.01)], src head conv3 -> [N, 1, h, w], cls head
// conv with kernel (h, w) -> [N, C]. Training goes through the autodiff tape (forward); generator::infer
// runs the kernels directly with a preallocated workspace (no tape, no allocation).
#pragma once

#include <handemo/autodiff.hpp>
#include <handemo/core/error.hpp>
#include <handemo/core/thread_pool.hpp>
#include <handemo/kernels/activation.hpp>
#include <handemo/kernels/norm.hpp>
#include <handemo/kernels/packed.hpp>
#include <handemo/kernels/winograd.hpp>
#include <handemo/tensor/aligned.hpp>
#include <handemo/tensor/shape.hpp>

#include <array>
#include <cmath>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace handemo::stargan {

using autodiff::tape;
using autodiff::var;

// ------------------------------------------------------------------------------------------ configs
/// @brief Configuration concept: joints J, keyframes K, domains C, conv_dim, res_blocks, d_repeat, batch.
template <class C>
concept stargan_config = requires {
    { C::joints } -> std::convertible_to<std::size_t>;
    { C::keyframes } -> std::convertible_to<std::size_t>;
    { C::domains } -> std::convertible_to<std::size_t>;
    { C::conv_dim } -> std::convertible_to<std::size_t>;
    { C::res_blocks } -> std::convertible_to<std::size_t>;
    { C::d_repeat } -> std::convertible_to<std::size_t>;
    { C::batch } -> std::convertible_to<std::size_t>;
};

/// @brief Hand, embedded size (the default of handemo's tools): 23 joints, 9 keyframes, 5 emotions.
struct hand_embedded {
    static constexpr std::size_t joints = 23, keyframes = 9, domains = 5, conv_dim = 32, res_blocks = 3,
                                 d_repeat = 3, batch = 1;
};
/// @brief Hand, the paper's StarGAN size (conv_dim 64, 6 residual blocks).
struct hand_paper {
    static constexpr std::size_t joints = 23, keyframes = 9, domains = 5, conv_dim = 64, res_blocks = 6,
                                 d_repeat = 3, batch = 1;
};
/// @brief Body (22 joints, 8 emotion classes), embedded size.
struct body_embedded {
    static constexpr std::size_t joints = 22, keyframes = 9, domains = 8, conv_dim = 32, res_blocks = 3,
                                 d_repeat = 3, batch = 1;
};
/// @brief Hand, microcontroller size (a glove's Cortex-M7): hand_embedded at a quarter of the width
/// (conv_dim 8, 3 residual blocks), 80,632 parameters = 322,528 bytes of float weights, so the weights fit in
/// flash as float and the activations of one inference in 30 KB of RAM (handemo::micro::generator).
struct hand_micro {
    static constexpr std::size_t joints = 23, keyframes = 9, domains = 5, conv_dim = 8, res_blocks = 3,
                                 d_repeat = 3, batch = 1;
};
/// @brief Any config with another batch size: `with_batch<hand_embedded, 16>`.
template <stargan_config Config, std::size_t N>
struct with_batch : Config {
    static constexpr std::size_t batch = N;
};

/// @brief Sizes derived from a config.
/// The image is padded to multiples of 4 = 2^2: the generator's two stride-2 4x4 convolutions and two
/// stride-2 transposed convolutions return exactly the input size only when H and W are divisible by 4
/// (9 x 23 -> 12 x 24, reference_stargan.py's H = 12, W = 24). D's d_repeat stride-2 4x4 pad-1 convs
/// floor odd sizes (12 -> 6 -> 3 -> 1, 24 -> 12 -> 6 -> 3) and its cls head takes whatever map remains
/// as its kernel, so D needs no further divisibility.
template <stargan_config Config>
struct dims {
    static constexpr std::size_t N = Config::batch, C = Config::domains, K = Config::keyframes,
                                 J = Config::joints, cd = Config::conv_dim, R = Config::res_blocks,
                                 rep = Config::d_repeat;
    static constexpr std::size_t H = round_up(K, 4), W = round_up(J, 4);
    /// D's feature map after layer i (0 = the input)
    static constexpr std::size_t d_h(std::size_t i) { return i == 0 ? H : conv_out(d_h(i - 1), 4, 2, 1); }
    static constexpr std::size_t d_w(std::size_t i) { return i == 0 ? W : conv_out(d_w(i - 1), 4, 2, 1); }
    static constexpr std::size_t d_ch(std::size_t i) { return i == 0 ? 3 : cd << (i - 1); }
    static constexpr std::size_t Hd = d_h(rep), Wd = d_w(rep), Cd = d_ch(rep);
    static_assert(H % 4 == 0 && W % 4 == 0, "stargan: padded image must be divisible by 4");
    static_assert(Hd >= 1 && Wd >= 1, "stargan: image too small for d_repeat stride-2 convolutions");
};

namespace detail {

/// One named parameter inside a model's flat value/grad buffers.
struct param_entry {
    std::string name;
    std::size_t offset = 0, size = 0;
    std::vector<std::size_t> shape;
};

/// Flat parameter storage (values and grads, 64-byte aligned entries) with PyTorch names.
template <class T>
class param_store {
public:
    void add(std::string name, std::vector<std::size_t> shape)
    {
        std::size_t n = 1;
        for (std::size_t d : shape) n *= d;
        entries_.push_back({std::move(name), total_, n, std::move(shape)});
        total_ += (n + 15) / 16 * 16;
    }
    void finish()
    {
        values_ = aligned_buffer<T>(total_);
        grads_ = aligned_buffer<T>(total_);
    }
    T* value(std::size_t i) noexcept { return values_.data() + entries_[i].offset; }
    const T* value(std::size_t i) const noexcept { return values_.data() + entries_[i].offset; }
    T* grad(std::size_t i) noexcept { return grads_.data() + entries_[i].offset; }
    /// Elements of the flat value (and grad) buffer, entries padded to 16.
    std::size_t total() const noexcept { return total_; }
    T* grads() noexcept { return grads_.data(); }
    const T* value_data() const noexcept { return values_.data(); }
    std::size_t count() const noexcept { return entries_.size(); }
    const param_entry& entry(std::size_t i) const noexcept { return entries_[i]; }
    template <class F>
    void for_each(F&& f)
    {
        for (std::size_t i = 0; i < entries_.size(); ++i)
            f(std::string_view(entries_[i].name), std::span<T>(value(i), entries_[i].size),
              std::span<T>(grad(i), entries_[i].size), std::span<const std::size_t>(entries_[i].shape));
    }
    void zero_grad() noexcept
    {
        if (total_) std::memset(grads_.data(), 0, total_ * sizeof(T));
    }
    std::size_t numel() const noexcept
    {
        std::size_t n = 0;
        for (const auto& e : entries_) n += e.size;
        return n;
    }

private:
    std::vector<param_entry> entries_;
    std::size_t total_ = 0;
    aligned_buffer<T> values_, grads_;
};


/// Parameter storage and the parameter API shared by the generator and the discriminator.
template <class T>
class parameter_owner {
public:
    /// @brief Calls f(name, value, grad, shape) for every parameter, in PyTorch state_dict order.
    template <class F>
    void for_each_parameter(F&& f)
    {
        p_.for_each(f);
    }
    /// @brief Sets every parameter gradient to zero (every gradient shard's too).
    void zero_grad() noexcept
    {
        p_.zero_grad();
        for (auto& b : shards_) std::memset(b.data(), 0, b.size() * sizeof(T));
    }
    /// @brief Data-parallel training: `s` gradient shards. forward(..., shard) of shard k accumulates its
    /// parameter gradients into shard k's buffer (shard 0: the gradients for_each_parameter gives), so that
    /// k tapes can run a batch's k parts on k threads at once; reduce_grad_shards() then adds them up.
    void set_grad_shards(std::size_t s)
    {
        if (s == 0) throw value_error("set_grad_shards: 0 shards (at least 1)");
        shards_.clear();
        for (std::size_t k = 1; k < s; ++k) shards_.emplace_back(std::max<std::size_t>(p_.total(), 1));
    }
    /// @brief Gradient += shard 1 + shard 2 + ... element by element in shard order, the elements split over
    /// `pool` (nullptr: this thread): the same sums on any number of threads.
    void reduce_grad_shards(thread_pool* pool = nullptr)
    {
        if (shards_.empty()) return;
        T* g = p_.grads();
        auto add = [&](std::size_t lo, std::size_t hi) {
            for (const auto& b : shards_) {
                const T* src = b.data();
                for (std::size_t i = lo; i < hi; ++i) g[i] += src[i];
            }
        };
        if (pool) parallel_blocks(*pool, p_.total(), add);
        else add(0, p_.total());
    }
    /// @brief Gradient shard `k`'s flat buffer (set_grad_shards; 0: the gradients for_each_parameter gives), every
    /// entry padded to 16 values: what data parallelism across processes shares before reduce_grad_shards().
    std::span<T> grad_shard(std::size_t k)
    {
        if (k > shards_.size())
            throw value_error("grad_shard: shard " + std::to_string(k) + " of " + std::to_string(shards_.size() + 1) + " (set_grad_shards)");
        return k == 0 ? std::span<T>(p_.grads(), p_.total()) : std::span<T>(shards_[k - 1].data(), p_.total());
    }
    /// @brief Whether forward() makes parameters trainable leaves (false: constants, no weight grads).
    void set_requires_grad(bool on) noexcept { requires_grad_ = on; }
    /// @brief Number of scalar parameters.
    std::size_t parameter_count() const noexcept { return p_.numel(); }
    /// @brief The flat buffer every parameter's values live in (entries padded to 16 values): what a tape may keep
    /// its packed panels of across a reset while these values do not change (tape::reset_keeping_packed).
    std::span<const T> parameter_values() const noexcept { return {p_.value_data(), p_.total()}; }

protected:
    T* grad_or_null(std::size_t i, std::size_t shard = 0)
    {
        if (!requires_grad_) return nullptr;
        if (shard == 0) return p_.grad(i);
        if (shard > shards_.size())
            throw value_error("forward: gradient shard " + std::to_string(shard) + " of " + std::to_string(shards_.size() + 1) +
                              " (set_grad_shards)");
        return shards_[shard - 1].data() + p_.entry(i).offset;
    }
    param_store<T> p_;
    std::vector<aligned_buffer<T>> shards_;  ///< gradient shards 1..s-1 (set_grad_shards)
    bool requires_grad_ = true;
};

/// In-place InstanceNorm (affine, biased variance) and optional ReLU over [N, C, M]. Used by infer().
template <class T>
void instance_norm_relu_inplace(T* x, const T* gamma, const T* beta, int N, int C, int M, bool relu,
                                T eps = T(1e-5)) noexcept
{
    for (int b = 0; b < N; ++b) kernels::instance_norm_per_channel(x + std::size_t(b) * C * M, gamma, beta, C, M, relu, eps);
}

}  // namespace detail

/// @brief Calls f(a_values, b_values) with the value spans of each parameter of two models of the same
/// layout (e.g. G and its moving average), in state_dict order.
template <class T, class F>
void zip_parameters(detail::parameter_owner<T>& a, detail::parameter_owner<T>& b, F&& f)
{
    std::vector<std::span<T>> src;
    a.for_each_parameter([&](std::string_view, std::span<T> v, std::span<T>, auto) { src.push_back(v); });
    std::size_t i = 0;
    b.for_each_parameter([&](std::string_view, std::span<T> v, std::span<T>, auto) { f(std::span<const T>(src.at(i++)), v); });
}

// ------------------------------------------------------------------------------------------ generator
template <class T, stargan_config Config>
class frozen_generator;

/// @brief StarGAN generator G(x, c): [N, 3, H, W] image and one-hot target [N, C] -> [N, 3, H, W] in (-1, 1).
/// @tparam T float or double
/// @tparam Config a stargan_config (hand_embedded, hand_paper, body_embedded, with_batch<...>)
template <class T, stargan_config Config>
class generator : public detail::parameter_owner<T> {
    using detail::parameter_owner<T>::p_;
    using detail::parameter_owner<T>::grad_or_null;

public:
    using dims_type = dims<Config>;
    static constexpr std::size_t N = dims_type::N, C = dims_type::C, H = dims_type::H, W = dims_type::W,
                                 cd = dims_type::cd, R = dims_type::R;
    using image_shape = shape<N, 3, H, W>;
    using label_shape = shape<N, C>;

    /// @brief Allocates the parameters (all zero; initialise them through for_each_parameter).
    generator()
    {
        auto conv = [&](std::string name, std::size_t o, std::size_t i, std::size_t k) {
            p_.add(std::move(name) + ".weight", {o, i, k, k});
        };
        auto norm = [&](const std::string& name, std::size_t c) {
            p_.add(name + ".weight", {c});
            p_.add(name + ".bias", {c});
        };
        conv("main.0", cd, 3 + C, 7);
        norm("main.1", cd);
        conv("main.3", 2 * cd, cd, 4);
        norm("main.4", 2 * cd);
        conv("main.6", 4 * cd, 2 * cd, 4);
        norm("main.7", 4 * cd);
        for (std::size_t r = 0; r < R; ++r) {
            const std::string b = "main." + std::to_string(9 + r) + ".main.";
            conv(b + "0", 4 * cd, 4 * cd, 3);
            norm(b + "1", 4 * cd);
            conv(b + "3", 4 * cd, 4 * cd, 3);
            norm(b + "4", 4 * cd);
        }
        p_.add("main." + std::to_string(9 + R) + ".weight", {4 * cd, 2 * cd, 4, 4});  // ConvTranspose [in, out, k, k]
        norm("main." + std::to_string(10 + R), 2 * cd);
        p_.add("main." + std::to_string(12 + R) + ".weight", {2 * cd, cd, 4, 4});
        norm("main." + std::to_string(13 + R), cd);
        conv("main." + std::to_string(15 + R), 3, cd, 7);
        p_.finish();
    }


    /// @brief Records G(x, label) on the tape.
    /// @param x [M, 3, H, W] padded motion images  @param label [M, C] one-hot target domains; any batch M
    /// (data-parallel training runs the config's N in parts)
    /// @param shard whose gradient buffer the parameters accumulate into (set_grad_shards)
    template <std::size_t M>
    var<T, shape<M, 3, H, W>> forward(tape<T>& t, const var<T, shape<M, 3, H, W>>& x, const var<T, shape<M, C>>& label,
                                      std::size_t shard = 0)
    {
        using namespace handemo::autodiff;
        using autodiff::tanh;
        std::size_t k = 0;
        auto w = [&]<class S>() { ++k; return t.template parameter<S>(p_.value(k - 1), grad_or_null(k - 1, shard)); };
        auto in_relu = [&]<std::size_t Ch, class V>(const V& v, bool with_relu) {
            auto g = w.template operator()<shape<Ch>>();
            auto b = w.template operator()<shape<Ch>>();
            auto y = instance_norm(v, g, b);
            return with_relu ? relu(y) : y;
        };
        auto h0 = concat_channels(x, tile<H, W>(label));
        auto h1 = in_relu.template operator()<cd>(conv2d<1, 3>(h0, w.template operator()<shape<cd, 3 + C, 7, 7>>()), true);
        auto h2 = in_relu.template operator()<2 * cd>(conv2d<2, 1>(h1, w.template operator()<shape<2 * cd, cd, 4, 4>>()), true);
        auto h = in_relu.template operator()<4 * cd>(conv2d<2, 1>(h2, w.template operator()<shape<4 * cd, 2 * cd, 4, 4>>()), true);
        for (std::size_t r = 0; r < R; ++r) {
            auto a = in_relu.template operator()<4 * cd>(conv2d<1, 1>(h, w.template operator()<shape<4 * cd, 4 * cd, 3, 3>>()), true);
            auto b = in_relu.template operator()<4 * cd>(conv2d<1, 1>(a, w.template operator()<shape<4 * cd, 4 * cd, 3, 3>>()), false);
            h = h + b;
        }
        auto u1 = in_relu.template operator()<2 * cd>(conv_transpose2d<2, 1>(h, w.template operator()<shape<4 * cd, 2 * cd, 4, 4>>()), true);
        auto u2 = in_relu.template operator()<cd>(conv_transpose2d<2, 1>(u1, w.template operator()<shape<2 * cd, cd, 4, 4>>()), true);
        auto y = tanh(conv2d<1, 3>(u2, w.template operator()<shape<3, cd, 7, 7>>()));
        if (residual_) return x + y;
        return y;
    }

    /// @brief Residual output (beyond the paper): G(x, c) = x + tanh(last conv) instead of tanh(last conv).
    /// With the last convolution at zero (zero_last_conv()) G is then exactly the identity.
    void set_residual(bool on) noexcept { residual_ = on; }
    bool residual() const noexcept { return residual_; }
    /// @brief Sets the weights of the last 7x7 convolution to zero.
    void zero_last_conv() noexcept
    {
        const std::size_t i = p_.count() - 1;
        std::fill_n(p_.value(i), p_.entry(i).size, T(0));
    }

    /// @brief Buffers for infer(): sized at construction, reused by every call.
    class workspace {
    public:
        workspace() : buf_(activation_buffers())
        {
            std::size_t s = 0;
            for (const auto& g : geometries()) s = std::max(s, kernels::conv2d_scratch_size<T>(g));
            scratch_ = aligned_buffer<T>(std::max<std::size_t>(s, 1));
        }

    private:
        friend class generator;
        std::array<aligned_buffer<T>, 4> buf_;
        aligned_buffer<T> scratch_;
    };

    /// @brief G(x, label) without a tape, single-threaded, no allocation. For many calls with the same
    /// weights, frozen_generator (freeze()) is faster: it packs the weights once.
    /// @param x [N, 3, H, W]  @param label [N, C]  @param out [N, 3, H, W] (written)
    void infer(const T* x, const T* label, T* out, workspace& ws) const
    {
        const auto g = geometries();
        T* s = ws.scratch_.data();
        std::size_t k = 0;
        auto conv = [&](std::size_t i, const T* in, T* o, std::size_t) {
            kernels::conv2d_forward<T>(g[i], in, p_.value(k++), static_cast<const T*>(nullptr), o, s);
        };
        auto convt = [&](std::size_t i, const T* in, T* o, std::size_t) {
            std::memset(o, 0, g[i].x_size() * sizeof(T));
            kernels::conv2d_backward_data<T>(g[i], in, p_.value(k++), o, s);
        };
        auto norm = [&](T* v, int images, int ch, int m, bool with_relu) {
            detail::instance_norm_relu_inplace(v, p_.value(k), p_.value(k + 1), images, ch, m, with_relu);
            k += 2;
        };
        auto first = [&](const T* xi, const T* li, T* o, std::size_t n, T* tmp) {
            tile_input(xi, li, tmp, n);
            conv(0, tmp, o, n);
        };
        run_layers(x, label, out, N, ws.buf_, first, conv, convt, norm, residual_);
    }

    /// @brief The four activation buffers run_layers() needs, each the size of the largest activation
    /// (max(conv_dim, 3 + domains) channels of the H x W image) of `images` images.
    static std::array<aligned_buffer<T>, 4> activation_buffers(std::size_t images = N)
    {
        const std::size_t act = std::max<std::size_t>(images, 1) * std::max<std::size_t>(cd, 3 + C) * H * W;
        return {aligned_buffer<T>(act), aligned_buffer<T>(act), aligned_buffer<T>(act), aligned_buffer<T>(act)};
    }

    /// @brief G's input on `n` images: each image's 3 channels followed by its label tiled as C constant
    /// channels, [n, 3 + C, H, W] into `a`.
    static void tile_input(const T* x, const T* label, T* a, std::size_t n_images) noexcept
    {
        const std::size_t HW = H * W;
        for (std::size_t n = 0; n < n_images; ++n) {
            std::memcpy(a + n * (3 + C) * HW, x + n * 3 * HW, 3 * HW * sizeof(T));
            for (std::size_t k = 0; k < C; ++k)
                std::fill_n(a + (n * (3 + C) + 3 + k) * HW, HW, label[n * C + k]);
        }
    }

    /// @brief The layer sequence of infer() on `n` images with the convolutions and norms given as callables:
    /// first(x, label, out, n, tmp) writes the first convolution's output on the image and its tiled label
    /// ([n, cd, H, W]; tmp: an activation buffer it may use), conv(i, in, out, n) and convt(i, in, out, n) for
    /// geometries()[i] on n images, norm(v, n, channels, pixels, relu), each called in parameter order. buf:
    /// four activation buffers of at least n images.
    template <class First, class Conv, class ConvT, class Norm>
    static void run_layers(const T* x, const T* label, T* out, std::size_t n_images, std::array<aligned_buffer<T>, 4>& buf,
                           First&& first, Conv&& conv, ConvT&& convt, Norm&& norm, bool residual)
    {
        T* a = buf[0].data();
        T* b = buf[1].data();
        T* c = buf[2].data();
        T* d = buf[3].data();
        const std::size_t HW = H * W;
        first(x, label, b, n_images, a);
        norm(b, int(n_images), int(cd), int(HW), true);
        conv(1, b, a, n_images);
        norm(a, int(n_images), int(2 * cd), int(HW / 4), true);
        conv(2, a, b, n_images);
        norm(b, int(n_images), int(4 * cd), int(HW / 16), true);
        const std::size_t m16 = n_images * 4 * cd * HW / 16;
        for (std::size_t r = 0; r < R; ++r) {
            conv(3, b, c, n_images);
            norm(c, int(n_images), int(4 * cd), int(HW / 16), true);
            conv(3, c, d, n_images);
            norm(d, int(n_images), int(4 * cd), int(HW / 16), false);
            for (std::size_t i = 0; i < m16; ++i) b[i] += d[i];
        }
        convt(4, b, a, n_images);
        norm(a, int(n_images), int(2 * cd), int(HW / 4), true);
        convt(5, a, c, n_images);
        norm(c, int(n_images), int(cd), int(HW), true);
        conv(6, c, out, n_images);
        kernels::tanh_inplace(out, n_images * 3 * HW, residual ? x : nullptr);
    }

    /// @brief A snapshot of the weights packed for fast repeated inference (see frozen_generator).
    /// storage f16: the convolution weights rounded to binary16 (kernels::weight_storage). algorithm winograd:
    /// the residual 3x3 convolutions by Winograd's minimal filtering (kernels::conv_algorithm; faster on batches).
    frozen_generator<T, Config> freeze(kernels::weight_storage storage = kernels::weight_storage::native,
                                       kernels::conv_algorithm algorithm = kernels::conv_algorithm::direct) const
    {
        return frozen_generator<T, Config>(*this, storage, algorithm);
    }

    /// @brief Multiply-adds of one forward pass (for GFLOP/s counters).
    static double forward_macs() noexcept
    {
        const auto g = geometries();
        return g[0].macs() + g[1].macs() + g[2].macs() + 2.0 * R * g[3].macs() + g[4].macs() + g[5].macs() +
               g[6].macs();
    }

    /// @brief Convolution geometries: conv7, down1, down2, residual conv3, up1 and up2 (as the adjoint
    /// conv), final conv7.
    static std::array<kernels::conv_geometry, 7> geometries() noexcept
    {
        const int n = int(N), h = int(H), w = int(W), c = int(cd);
        return {{{n, int(3 + C), h, w, c, 7, 7, 1, 3},
                 {n, c, h, w, 2 * c, 4, 4, 2, 1},
                 {n, 2 * c, h / 2, w / 2, 4 * c, 4, 4, 2, 1},
                 {n, 4 * c, h / 4, w / 4, 4 * c, 3, 3, 1, 1},
                 {n, 2 * c, h / 2, w / 2, 4 * c, 4, 4, 2, 1},
                 {n, c, h, w, 2 * c, 4, 4, 2, 1},
                 {n, c, h, w, 3, 7, 7, 1, 3}}};
    }

private:
    friend class frozen_generator<T, Config>;
    bool residual_ = false;
};

/// @brief G with its weights packed once for inference (kernels::packed_conv: the weight-stationary
/// kernels): the same G(x, label) as generator::infer up to the order of floating-point sums, 1.5-2x faster
/// at batch 1 (README, "Performance"). A snapshot: later changes to the generator do not reach it (freeze
/// again after training or loading). infer() is const and allocates nothing; one workspace per thread.
template <class T, stargan_config Config>
class frozen_generator {
public:
    using generator_type = generator<T, Config>;
    static constexpr std::size_t N = generator_type::N, C = generator_type::C, H = generator_type::H,
                                 W = generator_type::W, cd = generator_type::cd, R = generator_type::R;

    /// @brief Packs the weights of g (and copies its norm parameters and residual flag). storage f16: every
    /// convolution weight rounded to binary16 (kernels::weight_storage; half the bytes per inference where
    /// the kernels widen binary16 natively), the norm parameters and activations staying in T.
    /// algorithm winograd: the residual blocks' 3x3 convolutions by kernels::winograd_conv3x3 (where it takes
    /// their geometry: a SIMD type and a multiple of the SIMD width of channels), the tiles of up to its group()
    /// images per GEMM: 1.4-1.7x the direct path's throughput at batch 32 where measured, no slower at batch 1
    /// (docs/performance.md). Its results differ from direct's in the last bits; infer() and infer_batch() of one
    /// frozen generator still give an image the same bits.
    /// @throws value_error with weight_storage::f16 when a weight does not fit binary16 (naming it).
    explicit frozen_generator(const generator_type& g, kernels::weight_storage storage = kernels::weight_storage::native,
                              kernels::conv_algorithm algorithm = kernels::conv_algorithm::direct)
        : residual_(g.residual_)
    {
        const auto geo = generator_type::geometries();
        const bool winograd = algorithm == kernels::conv_algorithm::winograd && kernels::winograd_conv3x3<T>::supported(geo[3]);
        std::size_t k = 0;
        auto conv = [&](std::size_t i, bool transposed) {
            const T* w = g.p_.value(k);
            try {
                if (i == 3 && winograd) wino_.emplace_back(geo[i], w, storage);
                else
                    convs_.push_back(transposed ? kernels::packed_conv<T>::conv_transpose2d(geo[i], w, storage)
                                                : kernels::packed_conv<T>::conv2d(geo[i], w, storage));
            } catch (const value_error& e) {
                throw value_error("frozen_generator: parameter " + g.p_.entry(k).name + ": " + e.what());
            }
            ++k;
        };
        auto norm = [&]() {
            const std::size_t n = g.p_.entry(k).size;
            norms_.emplace_back(std::vector<T>(g.p_.value(k), g.p_.value(k) + n), std::vector<T>(g.p_.value(k + 1), g.p_.value(k + 1) + n));
            k += 2;
        };
        first_layer(g.p_.value(0), g.p_.entry(0).name, storage);
        ++k;
        norm(), conv(1, false), norm(), conv(2, false), norm();
        for (std::size_t r = 0; r < R; ++r) conv(3, false), norm(), conv(3, false), norm();
        conv(4, true), norm(), conv(5, true), norm(), conv(6, false);
    }

    /// @brief Buffers for infer() and infer_batch() of one frozen generator: sized at construction for
    /// `images` images at most (at least N, the configuration's batch), reused by every call.
    class workspace {
    public:
        explicit workspace(const frozen_generator& f, std::size_t images = N)
            : images_(std::max<std::size_t>(images, N)), buf_(generator_type::activation_buffers(images_))
        {
            std::size_t s = 1;
            for (const auto& c : f.convs_) s = std::max(s, c.scratch_size());
            for (const auto& c : f.wino_) s = std::max(s, c.scratch_size());
            scratch_ = aligned_buffer<T>(s);
        }
        /// @brief The most images one infer_batch() call with this workspace takes.
        std::size_t capacity() const noexcept { return images_; }

    private:
        friend class frozen_generator;
        std::size_t images_;
        std::array<aligned_buffer<T>, 4> buf_;
        aligned_buffer<T> scratch_;
    };

    /// @brief G(x, label): x [N, 3, H, W], label [N, C], out [N, 3, H, W] (written). No allocation.
    void infer(const T* x, const T* label, T* out, workspace& ws) const { run(x, label, out, N, ws); }

    /// @brief G on a batch of `images` images whatever the configuration's N: x [images, 3, H, W], label
    /// [images, C], out [images, 3, H, W] (written). No allocation. Each layer runs over the whole batch
    /// before the next one starts, so a layer's packed weights stay in cache from one image to the next;
    /// every image gets the bits infer() gives it alone (each convolution and InstanceNorm works image by image).
    /// @throws value_error when images is 0 or more than ws.capacity() (a workspace made for fewer images).
    void infer_batch(const T* x, const T* label, T* out, std::size_t images, workspace& ws) const
    {
        if (images == 0 || images > ws.capacity())
            throw value_error("frozen_generator::infer_batch: " + std::to_string(images) + " images, the workspace holds 1 to " +
                              std::to_string(ws.capacity()) + " (workspace(generator, images))");
        run(x, label, out, images, ws);
    }

    /// @brief The packed convolutions in network order (conv7, down1, down2, 2R residual convs, up1, up2, conv7;
    /// with conv_algorithm::winograd the residual convs are in winograd_convolutions() instead). The first is the
    /// 7x7 convolution over the image's 3 channels only: the label's C constant channels reach its output
    /// through label_maps().
    const std::vector<kernels::packed_conv<T>>& convolutions() const noexcept { return convs_; }
    /// @brief The residual blocks' 2R convolutions with conv_algorithm::winograd (empty with direct).
    const std::vector<kernels::winograd_conv3x3<T>>& winograd_convolutions() const noexcept { return wino_; }
    /// @brief The algorithm of the residual convolutions: winograd when it was asked for and takes their geometry.
    kernels::conv_algorithm algorithm() const noexcept
    {
        return wino_.empty() ? kernels::conv_algorithm::direct : kernels::conv_algorithm::winograd;
    }
    /// @brief What the first convolution adds for label channel k at value 1, [C, cd, H, W]: the convolution of
    /// a plane of ones (zero-padded as the image) with that channel's weights. It depends on the pixel only
    /// near the image's border, where the 7x7 window reaches the padding.
    std::span<const T> label_maps() const noexcept { return label_maps_; }
    /// @brief The weight storage asked for at construction (every convolution's).
    kernels::weight_storage storage() const noexcept { return convs_.front().storage(); }
    /// @brief Bytes of the convolution weights one inference streams (kernels::packed_conv::weight_bytes).
    std::size_t weight_bytes() const noexcept
    {
        std::size_t b = 0;
        for (const auto& c : convs_) b += c.weight_bytes();
        for (const auto& c : wino_) b += c.weight_bytes();
        return b;
    }

private:
    // The first convolution reads the image and the label tiled as C constant channels: of its (3 + C) 49
    // multiply-adds per output value, 49 C only add the label's weights over the part of the 7x7 window that
    // lies inside the image. They are done once here, per label channel, as the convolution of a plane of ones
    // (label_maps_); an inference convolves the 3 image channels and adds the maps of its label's channels,
    // the same sums in another order (a hand G: 62% of the first layer's multiply-adds, 7% of the network's).
    void first_layer(const T* w, const std::string& name, kernels::weight_storage storage)
    {
        const auto g0 = generator_type::geometries()[0];
        constexpr std::size_t taps = 7 * 7, in = 3 + C;
        std::vector<T> rounded;  // with f16 storage the maps too are made of the weights as stored
        if (storage == kernels::weight_storage::f16) {
            try {
                rounded = kernels::binary16_rounded(w, g0.w_size());
            } catch (const value_error& e) {
                throw value_error("frozen_generator: parameter " + name + ": " + e.what());
            }
            w = rounded.data();
        }
        std::vector<T> image_w(cd * 3 * taps), channel_w(cd * taps);
        for (std::size_t o = 0; o < cd; ++o)
            std::copy_n(w + o * in * taps, 3 * taps, image_w.begin() + std::ptrdiff_t(o * 3 * taps));
        kernels::conv_geometry gi = g0;
        gi.in_channels = 3;
        convs_.push_back(kernels::packed_conv<T>::conv2d(gi, image_w.data(), storage));
        const kernels::conv_geometry gm{1, 1, int(H), int(W), int(cd), 7, 7, 1, 3};
        std::vector<T> ones(H * W, T(1)), scratch(std::max<std::size_t>(kernels::conv2d_scratch_size<T>(gm), 1));
        label_maps_.assign(C * cd * H * W, T(0));
        for (std::size_t k = 0; k < C; ++k) {
            for (std::size_t o = 0; o < cd; ++o)
                std::copy_n(w + (o * in + 3 + k) * taps, taps, channel_w.begin() + std::ptrdiff_t(o * taps));
            kernels::conv2d_forward<T>(gm, ones.data(), channel_w.data(), static_cast<const T*>(nullptr),
                                       label_maps_.data() + k * cd * H * W, scratch.data());
        }
    }

    void run(const T* x, const T* label, T* out, std::size_t images, workspace& ws) const
    {
        T* s = ws.scratch_.data();
        std::size_t kc = 0, kn = 0, kw = 0;
        auto conv = [&](std::size_t i, const T* in, T* o, std::size_t n) {
            if (i == 3 && !wino_.empty()) wino_[kw++].forward(in, nullptr, o, s, n);
            else convs_[kc++].forward(in, nullptr, o, s, n);
        };
        auto norm = [&](T* v, int n, int ch, int m, bool with_relu) {
            const auto& [gamma, beta] = norms_[kn++];
            for (int b = 0; b < n; ++b)
                kernels::instance_norm_channels(v + std::ptrdiff_t(b) * ch * m, gamma.data(), beta.data(), ch, m, with_relu, T(1e-5));
        };
        auto first = [&](const T* xi, const T* li, T* o, std::size_t n, T*) {
            conv(0, xi, o, n);
            constexpr std::size_t M = cd * H * W;
            for (std::size_t i = 0; i < n; ++i)
                for (std::size_t k = 0; k < C; ++k) {
                    const T l = li[i * C + k];
                    if (l == T(0)) continue;
                    const T* m = label_maps_.data() + k * M;
                    T* y = o + i * M;
                    for (std::size_t j = 0; j < M; ++j) y[j] += l * m[j];
                }
        };
        generator_type::run_layers(x, label, out, images, ws.buf_, first, conv, conv, norm, residual_);
    }

    bool residual_;
    std::vector<T> label_maps_;
    std::vector<kernels::packed_conv<T>> convs_;
    std::vector<kernels::winograd_conv3x3<T>> wino_;
    std::vector<std::pair<std::vector<T>, std::vector<T>>> norms_;
};

// ------------------------------------------------------------------------------------------ discriminator
/// @brief StarGAN discriminator D(x) = (src [N, 1, Hd, Wd] real/fake scores, cls [N, C] domain logits).
template <class T, stargan_config Config>
class discriminator : public detail::parameter_owner<T> {
    using detail::parameter_owner<T>::p_;
    using detail::parameter_owner<T>::grad_or_null;

public:
    using dims_type = dims<Config>;
    static constexpr std::size_t N = dims_type::N, C = dims_type::C, H = dims_type::H, W = dims_type::W,
                                 rep = dims_type::rep, Hd = dims_type::Hd, Wd = dims_type::Wd,
                                 Cd = dims_type::Cd;
    using image_shape = shape<N, 3, H, W>;
    using src_shape = shape<N, 1, Hd, Wd>;
    using cls_shape = shape<N, C>;

    /// @brief Output of forward(): the two heads, for a batch of M images.
    template <std::size_t M>
    struct outputs_of {
        var<T, shape<M, 1, Hd, Wd>> src;
        var<T, shape<M, C>> cls;
    };
    using outputs = outputs_of<N>;

    /// @brief Allocates the parameters (all zero; initialise them through for_each_parameter).
    discriminator()
    {
        for (std::size_t i = 0; i < rep; ++i) {
            const std::string b = "main." + std::to_string(2 * i);
            p_.add(b + ".weight", {dims_type::d_ch(i + 1), dims_type::d_ch(i), 4, 4});
            p_.add(b + ".bias", {dims_type::d_ch(i + 1)});
        }
        p_.add("conv1.weight", {1, Cd, 3, 3});
        p_.add("conv2.weight", {C, Cd, Hd, Wd});
        p_.finish();
    }


    /// @brief Records D(x) on the tape.
    template <std::size_t M>
    outputs_of<M> forward(tape<T>& t, const var<T, shape<M, 3, H, W>>& x, std::size_t shard = 0)
    {
        auto h = layers<0>(t, x, shard);
        auto src = conv2d<1, 1>(h, t.template parameter<shape<1, Cd, 3, 3>>(p_.value(2 * rep), grad_or_null(2 * rep, shard)));
        auto cls = conv2d<1, 0>(h, t.template parameter<shape<C, Cd, Hd, Wd>>(p_.value(2 * rep + 1),
                                                                              grad_or_null(2 * rep + 1, shard)));
        return {src, var<T, shape<M, C>>{cls.t, cls.id}};
    }

    /// @brief Multiply-adds of one forward pass.
    static double forward_macs() noexcept
    {
        double m = 0;
        for (std::size_t i = 0; i < rep; ++i)
            m += double(N) * dims_type::d_ch(i + 1) * dims_type::d_h(i + 1) * dims_type::d_w(i + 1) *
                 dims_type::d_ch(i) * 16;
        return m + double(N) * Hd * Wd * Cd * 9 + double(N) * C * Cd * Hd * Wd;
    }

private:
    template <std::size_t I, class S>
    auto layers(tape<T>& t, const var<T, S>& x, std::size_t shard)
    {
        if constexpr (I == rep) {
            return x;
        } else {
            constexpr std::size_t co = dims_type::d_ch(I + 1), ci = dims_type::d_ch(I);
            auto w = t.template parameter<shape<co, ci, 4, 4>>(p_.value(2 * I), grad_or_null(2 * I, shard));
            auto b = t.template parameter<shape<co>>(p_.value(2 * I + 1), grad_or_null(2 * I + 1, shard));
            return layers<I + 1>(t, autodiff::leaky_relu(autodiff::conv2d<2, 1>(x, w, b), T(0.01)), shard);
        }
    }
};

}  // namespace handemo::stargan
