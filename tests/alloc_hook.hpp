// Replaces the global operator new/delete of a test program with versions that count allocations and
// record the largest one. Include it in exactly one translation unit of a program (replacement allocation
// functions cannot be inline), then read or reset the two counters.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace handemo_test {
inline std::atomic<long> alloc_count{0};            ///< operator new calls (all forms)
inline std::atomic<std::size_t> alloc_largest{0};   ///< largest single request, in bytes
inline void note_alloc(std::size_t n) noexcept
{
    ++alloc_count;
    std::size_t cur = alloc_largest.load();
    while (n > cur && !alloc_largest.compare_exchange_weak(cur, n)) {
    }
}
}  // namespace handemo_test

void* operator new(std::size_t n)
{
    handemo_test::note_alloc(n);
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, std::align_val_t a)
{
    handemo_test::note_alloc(n);
    const std::size_t al = static_cast<std::size_t>(a);
    if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
