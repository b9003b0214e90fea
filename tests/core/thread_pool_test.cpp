// thread_pool: every index runs exactly once, chunking is static (same index -> same thread every
// run, contiguous chunks), exceptions propagate. That the library's reductions through the pool are
// bitwise repeatable is tested on the library code itself: tests/autodiff/pool_determinism_test.cpp.
#include <doctest/doctest.h>

#include <handemo/core/thread_pool.hpp>

#include <atomic>
#include <type_traits>
#include <stdexcept>
#include <thread>
#include <vector>

namespace hk = handemo;

TEST_CASE("thread_pool runs each index once, on a fixed thread")
{
    for (unsigned n : {0u, 1u, 2u, 3u, 5u}) {
        hk::thread_pool pool(n);
        CHECK(pool.size() == (n == 0 ? 1u : n));
        for (int rep = 0; rep < 3; ++rep) {
            std::vector<std::atomic<int>> hits(1000);
            std::vector<std::thread::id> who1(1000), who2(1000);
            pool.parallel_for(0, 1000, [&](int i) { hits[std::size_t(i)]++; who1[std::size_t(i)] = std::this_thread::get_id(); });
            pool.parallel_for(0, 1000, [&](int i) { who2[std::size_t(i)] = std::this_thread::get_id(); });
            for (int i = 0; i < 1000; ++i) REQUIRE(hits[std::size_t(i)] == 1);
            CHECK(who1 == who2);
            // chunks are contiguous: the thread changes at most size()-1 times
            int changes = 0;
            for (int i = 1; i < 1000; ++i) changes += who1[std::size_t(i)] != who1[std::size_t(i - 1)];
            CHECK(changes <= int(pool.size()) - 1);
        }
        pool.parallel_for(5, 5, [&](int) { FAIL("empty range ran"); });
        std::atomic<int> sum{0};
        pool.parallel_for(-3, 4, [&](int i) { sum += i; });
        CHECK(sum == 0);
    }
}

TEST_CASE("thread_pool rethrows the exception of an iteration and stays usable")
{
    hk::thread_pool pool(2);
    CHECK_THROWS_AS(pool.parallel_for(0, 100, [](int i) { if (i == 77) throw std::runtime_error("boom"); }),
                    std::runtime_error);
    std::atomic<int> n{0};
    pool.parallel_for(0, 100, [&](int) { ++n; });
    CHECK(n == 100);
}


TEST_CASE("thread_pool: back-to-back calls (workers still spinning) and calls after a sleep both complete")
{
    // Waiting threads spin for spin_time, then sleep on a condition variable: calls that follow each other
    // at once find the workers spinning, calls after a pause longer than spin_time must wake them.
    hk::thread_pool pool(3);
    std::vector<int> hits(300, 0);
    for (int round = 0; round < 2000; ++round) {  // spinning path, many generations
        pool.parallel_for(0, 300, [&](int i) { ++hits[std::size_t(i)]; });
    }
    for (int h : hits) REQUIRE(h == 2000);
    for (int round = 0; round < 3; ++round) {  // sleeping path
        std::this_thread::sleep_for(hk::thread_pool::spin_time * 5);
        std::atomic<int> sum{0};
        pool.parallel_for(0, 100, [&](int i) { sum += i; });
        CHECK(sum.load() == 4950);
    }
    std::this_thread::sleep_for(hk::thread_pool::spin_time * 5);
    CHECK_THROWS_AS(pool.parallel_for(0, 9, [](int i) { if (i == 8) throw std::runtime_error("last"); }), std::runtime_error);
}

TEST_CASE("parallel_blocks: every element once, cut at multiples of 16, small ranges on the caller")
{
    for (unsigned threads : {1u, 2u, 3u})
        for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{17}, std::size_t{100000}, std::size_t{100003}}) {
            handemo::thread_pool pool(threads);
            std::vector<int> hits(n, 0);
            std::vector<std::pair<std::size_t, std::size_t>> parts(threads + 1, {0, 0});
            std::atomic<int> calls{0};
            handemo::parallel_blocks(pool, n, [&](std::size_t lo, std::size_t hi) {
                for (std::size_t i = lo; i < hi; ++i) ++hits[i];
                const int k = calls.fetch_add(1);
                parts[std::size_t(k)] = {lo, hi};
            });
            for (std::size_t i = 0; i < n; ++i) CHECK(hits[i] == 1);
            CHECK(calls.load() == (n == 0 ? 0 : n < (std::size_t{1} << 14) ? 1 : int(threads)));
            for (int k = 0; k < calls.load(); ++k) {
                CHECK(parts[std::size_t(k)].first % 16 == 0);
                CHECK((parts[std::size_t(k)].second % 16 == 0 || parts[std::size_t(k)].second == n));
            }
        }
}
