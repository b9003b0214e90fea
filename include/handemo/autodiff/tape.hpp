// The reverse-mode autodiff tape under handemo's StarGAN (Sec. 3.3 of the hand paper; the losses of
// StarGAN, Choi et al. 2018, Eq. 1-7 there, including the WGAN-GP term that needs double backward).
// Values and adjoints of every node live in an arena of 64-byte aligned blocks that is bump-allocated
// and rewound by reset() without freeing, so a training step after the first allocates nothing. Nodes
// are flat records {op name, backward function pointers, value/adjoint pointers, operand ids, the op's
// typed parameter record}; backward() is a plain reverse loop over them. grad(out, in) records the
// backward computation itself as new nodes (create_graph), so the gradient of a gradient is exact.
// Typed handles `var<T, shape<...>>` carry the shape in the type; the ops (ops.hpp, conv.hpp,
// norm.hpp) compute output shapes with constexpr functions and call the untyped node builders here.
#pragma once

#include <handemo/core/error.hpp>
#include <handemo/tensor/aligned.hpp>
#include <handemo/tensor/shape.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace handemo {
class thread_pool;
}

namespace handemo::autodiff {

template <class T>
class tape;

/// @brief A type an op may store as its parameter record in a node: a small trivially copyable struct
/// (a convolution geometry, a slope, a row layout) of at most node<T>::params_capacity bytes.
template <class P>
concept op_params = std::is_trivially_copyable_v<P> && std::is_default_constructible_v<P>;

namespace detail {
/// One object per parameter type; its address identifies the type a node's record holds.
template <class P>
inline constexpr char op_params_tag = 0;
}  // namespace detail

/// @brief One tape record. Ops fill `in` (differentiable operands), their own typed parameter record
/// (set_params / params: each op declares a struct, e.g. `affine_params<T>{scale, offset}`, and reads
/// back only that struct) and `aux` (arena memory saved for backward).
template <class T>
struct node {
    /// First-order backward: reads this node's adjoint, accumulates (+=) into its operands' adjoints.
    using backward_fn = void (*)(tape<T>&, int self);
    /// Graph backward: reads this node's grad node id and records nodes for its operands' grads.
    using graph_fn = void (*)(tape<T>&, int self);
    /// Bytes available to an op's parameter record (a conv2d geometry is 36).
    static constexpr std::size_t params_capacity = 48;

    const char* op = "leaf";
    backward_fn backward = nullptr;
    graph_fn backward_graph = nullptr;
    T* value = nullptr;
    T* adjoint = nullptr;
    std::size_t size = 0;
    int in[3] = {-1, -1, -1};
    T* aux = nullptr;
    int grad = -1;                  ///< grad(): id of the node holding d out / d this, or -1
    bool requires_grad = false;
    bool external_adjoint = false;  ///< adjoint is caller memory (a parameter's grad): never zeroed
    bool external_value = false;    ///< value is caller memory (a parameter), unchanged until the tape's reset()
    bool mark = false;              ///< scratch flag of backward()/grad()

    /// @brief Stores `p` as this node's parameter record (replacing any earlier one).
    template <op_params P>
    void set_params(const P& p) noexcept
    {
        static_assert(sizeof(P) <= params_capacity, "autodiff::node: parameter record larger than params_capacity");
        std::memcpy(params_, &p, sizeof(P));
        params_type_ = &detail::op_params_tag<P>;
    }
    /// @brief This node's parameter record, which must have been stored as a `P`.
    /// @throws value_error if the node holds no record or one of another type (a bug in an op).
    template <op_params P>
    P params() const
    {
        if (params_type_ != &detail::op_params_tag<P>)
            throw value_error(std::string("autodiff::node::params: node '") + op +
                              (params_type_ ? "' holds the parameter record of another type"
                                            : "' holds no parameter record"));
        P p;
        std::memcpy(&p, params_, sizeof(P));
        return p;
    }
    /// @brief True when the node's parameter record is a `P`.
    template <op_params P>
    bool holds_params() const noexcept
    {
        return params_type_ == &detail::op_params_tag<P>;
    }

private:
    alignas(8) unsigned char params_[params_capacity] = {};
    const void* params_type_ = nullptr;
};

/// @brief Typed handle of a tape node: element type and compile-time shape.
template <class T, shape_like S>
struct var {
    using value_type = T;
    using shape_type = S;
    static constexpr std::size_t size = S::size;

    tape<T>* t = nullptr;
    int id = -1;

    /// @brief The node's values, row-major, `size` elements.
    T* data() const noexcept { return t->at(id).value; }
    std::span<const T, size> value() const noexcept { return std::span<const T, size>(data(), size); }
    /// @brief The node's adjoint after backward() (nullptr when it does not require grad).
    const T* adjoint() const noexcept { return t->at(id).adjoint; }
    /// @brief The single value of a scalar.
    T item() const noexcept
        requires(S::size == 1)
    {
        return data()[0];
    }
    bool requires_grad() const noexcept { return t->at(id).requires_grad; }
};

/// @brief Reverse-mode tape with an arena reused across iterations.
/// @tparam T float or double
template <class T>
class tape {
public:
    /// @param block_elems elements per arena block (a request larger than a block gets its own block)
    /// @param pool optional thread pool; convolutions split their batch over it
    explicit tape(std::size_t block_elems = std::size_t{1} << 21, thread_pool* pool = nullptr)
        : block_elems_(block_elems), pool_(pool)
    {
        blocks_.reserve(256);
        nodes_.reserve(1024);
        packed_.reserve(64);
        slots_.reserve(64);
    }
    tape(const tape&) = delete;
    tape& operator=(const tape&) = delete;

    /// @brief Forgets every node and every packed() entry and rewinds the arena; keeps all memory for the next
    /// iteration.
    void reset() noexcept { reset_keeping_packed(nullptr, nullptr); }
    /// @brief As reset(), but keeps the packed() entries whose key lies in [begin, end): the caller's promise that
    /// that memory has not changed since they were packed (the trainer keeps G's panels from a step's D phase for
    /// its G phase, between which only D's weights change).
    void reset_keeping_packed(const void* begin, const void* end) noexcept
    {
        nodes_.clear();
        const auto lo = reinterpret_cast<std::uintptr_t>(begin), hi = reinterpret_cast<std::uintptr_t>(end);
        std::size_t kept = 0;
        for (const packed_entry& e : packed_) {
            const auto k = reinterpret_cast<std::uintptr_t>(e.key);
            if (lo <= k && k < hi)
                packed_[kept++] = e;
            else
                slots_[e.slot].used = false;
        }
        packed_.resize(kept);
        block_ = 0;
        used_ = 0;
    }

    thread_pool* pool() const noexcept { return pool_; }

    /// @brief `n` elements of 64-byte aligned arena memory (uninitialised), valid until reset().
    T* alloc(std::size_t n)
    {
        constexpr std::size_t line = tensor_alignment / sizeof(T);
        n = (n + line - 1) / line * line;
        if (n == 0) n = line;
        for (;;) {
            if (block_ < blocks_.size()) {
                if (used_ + n <= blocks_[block_].size()) {
                    T* p = blocks_[block_].data() + used_;
                    used_ += n;
                    return p;
                }
                ++block_;
                used_ = 0;
                continue;
            }
            blocks_.emplace_back(std::max(block_elems_, n));
        }
    }
    /// @brief `n` elements of 64-byte aligned memory (uninitialised) for the kernels of one operation while it runs:
    /// the same region at every call (grown when a call asks for more, then kept across reset()), so the
    /// convolutions' packed weights and padded images stay in cache from one call to the next instead of
    /// spreading over the arena. Valid until the next scratch() call: nothing an operation keeps lives there.
    T* scratch(std::size_t n)
    {
        if (scratch_.size() < n) scratch_ = aligned_buffer<T>(n);
        return scratch_.data();
    }
    /// @brief `n` elements (64-byte aligned) that fill(dst) writes from caller memory `key` for a use `kind` (a
    /// convolution's weights packed into panels), filled at the first request after reset() and the same memory at
    /// every later request for (key, kind, n) until reset(). Only for memory that does not change while the tape
    /// holds nodes reading it: a parameter's values (leaf_ref), which optimisers update between steps. The entries
    /// live outside the arena, in buffers kept across reset() and reused by size, so that reset_keeping_packed()
    /// can keep some and a step after the first allocates nothing.
    template <class Fill>
    const T* packed(const void* key, int kind, std::size_t n, Fill&& fill)
    {
        for (const packed_entry& e : packed_)
            if (e.key == key && e.kind == kind && e.n == n) return slots_[e.slot].buf.data();
        std::size_t best = slots_.size();
        for (std::size_t i = 0; i < slots_.size(); ++i)  // the smallest free buffer that holds n
            if (!slots_[i].used && slots_[i].buf.size() >= n && (best == slots_.size() || slots_[i].buf.size() < slots_[best].buf.size()))
                best = i;
        if (best == slots_.size()) slots_.push_back({aligned_buffer<T>(n), false});
        slots_[best].used = true;
        T* p = slots_[best].buf.data();
        fill(p);
        packed_.push_back({key, kind, n, best});
        return p;
    }
    /// @brief Entries packed() holds since the last reset().
    std::size_t packed_count() const noexcept { return packed_.size(); }
    /// @brief Whether the convolutions keep a parameter's packed panels for the tape's later convolutions
    /// (packed(); on by default). Off, every convolution packs its weights at the call: the same bits, more time,
    /// and none of the panels' memory (about the parameters' size, twice for G in training).
    void set_panel_cache(bool on) noexcept { panel_cache_ = on; }
    bool panel_cache() const noexcept { return panel_cache_; }
    /// @brief Zeroed arena memory.
    T* alloc_zero(std::size_t n)
    {
        T* p = alloc(n);
        std::memset(p, 0, n * sizeof(T));
        return p;
    }

    node<T>& at(int id) noexcept { return nodes_[static_cast<std::size_t>(id)]; }
    const node<T>& at(int id) const noexcept { return nodes_[static_cast<std::size_t>(id)]; }
    std::size_t node_count() const noexcept { return nodes_.size(); }
    /// @brief Bytes of arena memory held (all blocks).
    std::size_t arena_bytes() const noexcept
    {
        std::size_t b = 0;
        for (const auto& blk : blocks_) b += blk.size() * sizeof(T);
        return b;
    }

    /// @brief Adjoint of operand `id`, or nullptr when it needs none.
    T* adj(int id) noexcept { return id >= 0 && at(id).requires_grad ? at(id).adjoint : nullptr; }

    /// @brief Appends a node of `size` values computed from `inputs`; allocates its value and, when any
    /// input requires grad, its adjoint. Returns the id. The caller fills the values.
    int make(const char* op, std::size_t size, std::initializer_list<int> inputs,
             typename node<T>::backward_fn bw, typename node<T>::graph_fn gbw)
    {
        node<T> n;
        n.op = op;
        n.size = size;
        n.backward = bw;
        n.backward_graph = gbw;
        int k = 0;
        for (int i : inputs) {
            n.in[k++] = i;
            if (i >= 0 && at(i).requires_grad) n.requires_grad = true;
        }
        n.value = alloc(size);
        if (n.requires_grad) n.adjoint = alloc(size);
        nodes_.push_back(n);
        return static_cast<int>(nodes_.size() - 1);
    }
    /// @brief As make() above, with the op's parameter record `params` (read back by node::params<P>()).
    template <op_params P>
    int make(const char* op, std::size_t size, std::initializer_list<int> inputs,
             typename node<T>::backward_fn bw, typename node<T>::graph_fn gbw, const P& params)
    {
        const int id = make(op, size, inputs, bw, gbw);
        at(id).set_params(params);
        return id;
    }

    /// @brief A leaf holding a copy of `data` (or zeros when `data` is null).
    int leaf_copy(const T* data, std::size_t size, bool requires_grad)
    {
        node<T> n;
        n.size = size;
        n.value = alloc(size);
        if (data)
            std::memcpy(n.value, data, size * sizeof(T));
        else
            std::memset(n.value, 0, size * sizeof(T));
        n.requires_grad = requires_grad;
        if (requires_grad) n.adjoint = alloc(size);
        nodes_.push_back(n);
        return static_cast<int>(nodes_.size() - 1);
    }

    /// @brief A leaf over caller memory: values at `value`; gradients accumulate (+=) into `grad`
    /// (nullptr: the leaf does not require grad). Both must outlive the tape's use of the node, and the values
    /// must not change until reset(): the convolutions pack a parameter's weights once per tape (packed()).
    int leaf_ref(T* value, T* grad, std::size_t size)
    {
        node<T> n;
        n.op = "parameter";
        n.size = size;
        n.value = value;
        n.adjoint = grad;
        n.requires_grad = grad != nullptr;
        n.external_adjoint = true;
        n.external_value = true;
        nodes_.push_back(n);
        return static_cast<int>(nodes_.size() - 1);
    }

    /// @brief A constant leaf of `size` copies of `v`.
    int fill(T v, std::size_t size)
    {
        int id = leaf_copy(nullptr, size, false);
        std::fill_n(at(id).value, size, v);
        return id;
    }

    /// @brief Typed leaves (see leaf_copy / leaf_ref).
    template <shape_like S>
    var<T, S> input(const T* data, bool requires_grad = false)
    {
        return {this, leaf_copy(data, S::size, requires_grad)};
    }
    template <shape_like S>
    var<T, S> parameter(T* value, T* grad)
    {
        return {this, leaf_ref(value, grad, S::size)};
    }
    template <shape_like S>
    var<T, S> constant(T v)
    {
        return {this, fill(v, S::size)};
    }

    /// @brief First-order reverse sweep from the scalar `loss`: every node that requires grad and that
    /// `loss` depends on gets d loss / d node in its adjoint; parameters accumulate into their grad.
    /// @throws shape_error if `loss` is not a scalar.
    void backward(int loss)
    {
        if (at(loss).size != 1)
            throw shape_error("autodiff::backward: loss has " + std::to_string(at(loss).size) +
                              " elements, expected a scalar (1)");
        if (!at(loss).requires_grad) return;
        for (int i = 0; i <= loss; ++i) at(i).mark = false;
        at(loss).mark = true;
        for (int i = loss; i >= 0; --i) {
            node<T>& n = at(i);
            if (!n.mark || !n.requires_grad) continue;
            for (int j : n.in)
                if (j >= 0 && at(j).requires_grad) at(j).mark = true;
        }
        for (int i = 0; i <= loss; ++i) {  // every adjoint reads as 0 unless loss depends on the node
            node<T>& n = at(i);
            if (n.requires_grad && !n.external_adjoint) std::memset(n.adjoint, 0, n.size * sizeof(T));
        }
        at(loss).adjoint[0] += T(1);
        for (int i = loss; i >= 0; --i) {
            node<T>& n = at(i);
            if (n.mark && n.requires_grad && n.backward) n.backward(*this, i);
        }
    }
    template <shape_like S>
    void backward(const var<T, S>& loss)
    {
        static_assert(S::size == 1, "autodiff::backward: the loss must be a scalar");
        backward(loss.id);
    }

    /// @brief d out / d in as new tape nodes (PyTorch's autograd.grad with create_graph=True): the
    /// result is itself differentiable, so a loss built from it (the WGAN-GP penalty) backpropagates
    /// exactly into everything the gradient depends on (D's weights).
    /// @throws shape_error if `out` is not a scalar or was recorded before `in`; value_error if a node
    /// between them has no graph backward.
    int grad(int out, int in)
    {
        if (at(out).size != 1)
            throw shape_error("autodiff::grad: output has " + std::to_string(at(out).size) +
                              " elements, expected a scalar (1); sum it first");
        if (out < in) throw shape_error("autodiff::grad: output node recorded before the input node");
        for (int i = in; i <= out; ++i) {
            node<T>& n = at(i);
            n.grad = -1;
            n.mark = i == in;
            if (i != in)
                for (int j : n.in)
                    if (j >= in && at(j).mark) n.mark = true;
        }
        const std::size_t in_size = at(in).size;
        if (!at(out).mark) return fill(T(0), in_size);
        at(out).grad = fill(T(1), 1);
        for (int i = out; i > in; --i) {
            if (!at(i).mark || at(i).grad < 0) continue;
            if (!at(i).backward_graph)
                throw value_error(std::string("autodiff::grad: op '") + at(i).op +
                                  "' has no double backward (needed between output and input)");
            at(i).backward_graph(*this, i);
        }
        return at(in).grad >= 0 ? at(in).grad : fill(T(0), in_size);
    }
    template <shape_like SO, shape_like SI>
    var<T, SI> grad(const var<T, SO>& out, const var<T, SI>& in)
    {
        static_assert(SO::size == 1, "autodiff::grad: the output must be a scalar (sum it first)");
        return {this, grad(out.id, in.id)};
    }

    /// @brief Inside a graph backward: adds the gradient node `contribution` to operand `target`'s grad.
    void accumulate_grad(int target, int contribution);

private:
    struct packed_entry {
        const void* key;
        int kind;
        std::size_t n;
        std::size_t slot;  ///< index into slots_
    };
    struct packed_slot {
        aligned_buffer<T> buf;
        bool used;
    };
    std::vector<aligned_buffer<T>> blocks_;
    aligned_buffer<T> scratch_;
    std::vector<packed_entry> packed_;
    std::vector<packed_slot> slots_;
    bool panel_cache_ = true;
    std::size_t block_ = 0, used_ = 0, block_elems_;
    std::vector<node<T>> nodes_;
    thread_pool* pool_ = nullptr;
};

namespace detail {

// y = a + b.  d/da = g, d/db = g.
template <class T>
void add_backward(tape<T>& t, int self)
{
    const node<T>& n = t.at(self);
    const std::size_t m = n.size;
    if (T* ga = t.adj(n.in[0]))
        for (std::size_t i = 0; i < m; ++i) ga[i] += n.adjoint[i];
    if (T* gb = t.adj(n.in[1]))
        for (std::size_t i = 0; i < m; ++i) gb[i] += n.adjoint[i];
}
template <class T>
void add_graph(tape<T>& t, int self)
{
    const int g = t.at(self).grad, a = t.at(self).in[0], b = t.at(self).in[1];
    t.accumulate_grad(a, g);
    t.accumulate_grad(b, g);
}
/// Untyped y = a + b (same sizes).
template <class T>
int add_raw(tape<T>& t, int a, int b)
{
    const int id = t.make("add", t.at(a).size, {a, b}, &add_backward<T>, &add_graph<T>);
    const T *x = t.at(a).value, *y = t.at(b).value;
    T* z = t.at(id).value;
    for (std::size_t i = 0, m = t.at(id).size; i < m; ++i) z[i] = x[i] + y[i];
    return id;
}

}  // namespace detail

template <class T>
void tape<T>::accumulate_grad(int target, int contribution)
{
    if (target < 0 || !at(target).mark) return;
    if (at(target).grad < 0)
        at(target).grad = contribution;
    else
        at(target).grad = detail::add_raw(*this, at(target).grad, contribution);
}

}  // namespace handemo::autodiff
