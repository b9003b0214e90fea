// A small fixed-size thread pool with one primitive, parallel_for over an integer range with static
// chunking: iteration i always runs on the same worker for the same (begin, end, size()), so a reduction
// written per chunk is bit-for-bit deterministic. Used to spread a batch (or output channels) of the
// StarGAN convolutions (Chan et al. 2020, Sec. 3.3) over cores; the kernels themselves stay single-threaded.
// It lives in core/ because the autodiff tape and the StarGAN trainer hold one, not only the kernels.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <memory>
#include <type_traits>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace handemo {

/// @brief Fixed pool of `n - 1` worker threads plus the calling thread; parallel_for blocks until done.
/// Waiting threads spin for up to spin_time before they sleep on a condition variable: a training step
/// calls parallel_for hundreds of times with short serial work in between, and waking a sleeping thread
/// (a futex, and on a VM an interrupt to an idle vCPU) cost more than the work of the small layers.
class thread_pool {
public:
    /// @brief Starts n - 1 workers (n = 0 is treated as 1: everything runs on the caller).
    explicit thread_pool(unsigned n) : size_(n == 0 ? 1u : n)
    {
        workers_.reserve(size_ - 1);
        for (unsigned t = 1; t < size_; ++t) workers_.emplace_back([this, t] { worker_loop(t); });
    }
    thread_pool(const thread_pool&) = delete;
    thread_pool& operator=(const thread_pool&) = delete;
    ~thread_pool()
    {
        {
            std::lock_guard<std::mutex> lock(mutex_);
            stop_.store(true, std::memory_order_release);
        }
        start_cv_.notify_all();
        for (auto& w : workers_) w.join();
    }

    /// @brief Number of threads that run iterations (workers + the caller).
    unsigned size() const { return size_; }

    /// @brief Calls f(i) for every i in [begin, end). Static chunking: thread t gets the contiguous chunk
    /// [begin + t*len/size, begin + (t+1)*len/size). Not reentrant (do not call from inside f).
    /// @throws whatever f throws (the first exception, after every chunk finished).
    template <class F>
    void parallel_for(int begin, int end, F&& f)
    {
        if (end <= begin) return;
        if (size_ == 1 || end - begin == 1) {
            for (int i = begin; i < end; ++i) f(i);
            return;
        }
        using fn_t = std::remove_reference_t<F>;
        job_fn_ = [](void* ctx, int i) { (*static_cast<fn_t*>(ctx))(i); };
        job_ctx_ = const_cast<void*>(static_cast<const void*>(std::addressof(f)));
        job_begin_ = begin;
        job_end_ = end;
        error_ = nullptr;
        pending_.store(size_ - 1, std::memory_order_relaxed);
        {
            std::lock_guard<std::mutex> lock(mutex_);
            generation_.fetch_add(1, std::memory_order_release);
        }
        start_cv_.notify_all();
        run_chunk(0);
        if (!spin_until([this] { return pending_.load(std::memory_order_acquire) == 0; })) {
            std::unique_lock<std::mutex> lock(mutex_);
            done_cv_.wait(lock, [this] { return pending_.load(std::memory_order_acquire) == 0; });
        }
        if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
    }

    /// @brief How long a waiting thread spins before it sleeps.
    static constexpr std::chrono::microseconds spin_time{200};

private:
    void run_chunk(unsigned t)
    {
        const long len = long(job_end_) - job_begin_;
        const int lo = int(job_begin_ + len * t / size_), hi = int(job_begin_ + len * (t + 1) / size_);
        try {
            for (int i = lo; i < hi; ++i) job_fn_(job_ctx_, i);
        } catch (...) {
            std::lock_guard<std::mutex> lock(mutex_);
            if (!error_) error_ = std::current_exception();
        }
    }
    /// Spins until ready() or spin_time has passed; returns ready().
    template <class P>
    static bool spin_until(P&& ready)
    {
        const auto until = std::chrono::steady_clock::now() + spin_time;
        for (int n = 0;; ++n) {
            if (ready()) return true;
            if ((n & 63) == 63 && std::chrono::steady_clock::now() > until) return ready();
#if defined(__x86_64__) || defined(__i386__)
            __builtin_ia32_pause();
#elif defined(__aarch64__)
            __asm__ volatile("yield");
#endif
        }
    }
    void worker_loop(unsigned t)
    {
        unsigned long seen = 0;
        for (;;) {
            auto started = [&] {
                return stop_.load(std::memory_order_acquire) || generation_.load(std::memory_order_acquire) != seen;
            };
            if (!spin_until(started)) {
                std::unique_lock<std::mutex> lock(mutex_);
                start_cv_.wait(lock, started);
            }
            if (stop_.load(std::memory_order_acquire)) return;
            seen = generation_.load(std::memory_order_acquire);
            run_chunk(t);
            if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) {
                std::lock_guard<std::mutex> lock(mutex_);  // the caller may be between its check and its wait
                done_cv_.notify_one();
            }
        }
    }

    unsigned size_;
    std::vector<std::thread> workers_;
    std::mutex mutex_;
    std::condition_variable start_cv_, done_cv_;
    std::atomic<bool> stop_{false};
    std::atomic<unsigned long> generation_{0};
    std::atomic<unsigned> pending_{0};
    void (*job_fn_)(void*, int) = nullptr;
    void* job_ctx_ = nullptr;
    int job_begin_ = 0, job_end_ = 0;
    std::exception_ptr error_;
};

/// @brief Calls f(lo, hi) on pool.size() contiguous parts of [0, n), each thread one part, the cut points
/// multiples of 16 elements (a 64-byte line of floats), for element-wise loops over long arrays (the
/// optimiser, gradient reductions). Below `min_parallel` elements, f(0, n) on the caller.
template <class F>
void parallel_blocks(thread_pool& pool, std::size_t n, F&& f, std::size_t min_parallel = std::size_t{1} << 14)
{
    const std::size_t parts = pool.size();
    if (parts == 1 || n < min_parallel) {
        if (n) f(std::size_t{0}, n);
        return;
    }
    const std::size_t lines = (n + 15) / 16;
    pool.parallel_for(0, int(parts), [&](int k) {
        const std::size_t lo = std::min(n, lines * std::size_t(k) / parts * 16);
        const std::size_t hi = std::min(n, lines * std::size_t(k + 1) / parts * 16);
        if (hi > lo) f(lo, hi);
    });
}

}  // namespace handemo
