// 64-byte aligned heap storage shared by handemo's tensors and the autodiff arena: one cache line, the
// widest SIMD load handemo's kernels issue. No paper equation; plumbing for the StarGAN tensors.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <new>

namespace handemo {

/// @brief Alignment of every tensor buffer, in bytes.
inline constexpr std::size_t tensor_alignment = 64;

/// @brief The first tensor_alignment-aligned element at or after p: where a kernel starts the tiles it loads and
/// stores aligned in a scratch buffer given with any alignment (whose size counts tensor_alignment / sizeof(T)
/// elements more for it).
template <class T>
T* align_up(T* p) noexcept
{
    const auto a = reinterpret_cast<std::uintptr_t>(p);
    return reinterpret_cast<T*>((a + tensor_alignment - 1) / tensor_alignment * tensor_alignment);
}

namespace detail {

struct aligned_delete {
    void operator()(void* p) const noexcept { ::operator delete[](p, std::align_val_t{tensor_alignment}); }
};

}  // namespace detail

/// @brief Owning, 64-byte aligned array of `n` trivially copyable `T` (zero-initialised).
template <class T>
class aligned_buffer {
public:
    aligned_buffer() = default;
    explicit aligned_buffer(std::size_t n) : data_(allocate(n)), size_(n) {}
    aligned_buffer(const aligned_buffer& o) : data_(allocate(o.size_)), size_(o.size_)
    {
        if (size_) std::memcpy(data_.get(), o.data_.get(), size_ * sizeof(T));
    }
    aligned_buffer(aligned_buffer&&) noexcept = default;
    aligned_buffer& operator=(const aligned_buffer& o)
    {
        if (this != &o) *this = aligned_buffer(o);
        return *this;
    }
    aligned_buffer& operator=(aligned_buffer&&) noexcept = default;

    T* data() noexcept { return static_cast<T*>(data_.get()); }
    const T* data() const noexcept { return static_cast<const T*>(data_.get()); }
    std::size_t size() const noexcept { return size_; }

private:
    static void* allocate(std::size_t n)
    {
        if (n == 0) return nullptr;
        void* p = ::operator new[](n * sizeof(T), std::align_val_t{tensor_alignment});
        std::memset(p, 0, n * sizeof(T));
        return p;
    }
    std::unique_ptr<void, detail::aligned_delete> data_;
    std::size_t size_ = 0;
};

}  // namespace handemo
