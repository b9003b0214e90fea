// Shared by the fuzz harnesses of tests/fuzz/: each harness defines handemo_fuzz::<target>::run(data, size),
// which feeds the bytes to one reader of outside data and lets only handemo's own errors (handemo::error
// and its subclasses) through as "refused". Anything else escaping (std::out_of_range, bad_alloc,
// length_error, nlohmann exceptions), a sanitizer report, a hang or memory over -rss_limit_mb is a bug.
// Built two ways: with clang -fsanitize=fuzzer,address,undefined as one libFuzzer program per target
// (HANDEMO_FUZZ=ON), and, without libFuzzer, all harnesses in one ASan/UBSan program (replay.cpp plus every
// harness compiled with HANDEMO_FUZZ_REPLAY defined) that CTest runs over the committed corpora and regression files.
#pragma once

#include <handemo/core/error.hpp>

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace handemo_fuzz {

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) noexcept
{
    return {reinterpret_cast<const char*>(data), size};
}

/// Runs `f`, swallowing handemo's own errors (a refused input is a correct outcome).
template <class F>
int refuse_ok(F&& f)
{
    try {
        f();
    } catch (const handemo::error&) {
    }
    return 0;
}

}  // namespace handemo_fuzz

#ifdef HANDEMO_FUZZ_REPLAY
// The replay program compiles each harness as its own translation unit (so the build spreads them over the
// cores) and reaches it through this plain entry point, which replay.cpp declares.
#define HANDEMO_FUZZ_ENTRY(target)                                                              \
    int handemo_fuzz_replay_##target(const std::uint8_t* data, std::size_t size)               \
    {                                                                                           \
        return handemo_fuzz::target::run(data, size);                                           \
    }
#else
#define HANDEMO_FUZZ_ENTRY(target)                                                              \
    extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)          \
    {                                                                                           \
        return handemo_fuzz::target::run(data, size);                                           \
    }
#endif
