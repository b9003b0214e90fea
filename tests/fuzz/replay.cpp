// Replays fuzz corpora and regression files through the harnesses' plain entry points (no libFuzzer), so
// CTest (label fuzz-replay) runs them under ASan/UBSan with any compiler that has the sanitizers (GCC too).
// Usage: handemo_fuzz_replay <target> [--optional] <file or folder>...   (folders are walked recursively, sorted;
// a path after --optional may be missing)
// Exit 0 when every input is accepted or refused with a handemo error; anything else aborts.
// Each harness (bvh.cpp, checkpoint.cpp, ...) is a translation unit of this program of its own, compiled with
// HANDEMO_FUZZ_REPLAY defined (tests/fuzz/CMakeLists.txt), which makes HANDEMO_FUZZ_ENTRY define
// handemo_fuzz_replay_<target> instead of libFuzzer's entry point.
#include <handemo/core/io.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

#define HANDEMO_FUZZ_REPLAY_DECLARE(target) int handemo_fuzz_replay_##target(const std::uint8_t* data, std::size_t size);
HANDEMO_FUZZ_REPLAY_DECLARE(bvh)
HANDEMO_FUZZ_REPLAY_DECLARE(checkpoint)
HANDEMO_FUZZ_REPLAY_DECLARE(csv)
HANDEMO_FUZZ_REPLAY_DECLARE(glove)
HANDEMO_FUZZ_REPLAY_DECLARE(image)
HANDEMO_FUZZ_REPLAY_DECLARE(manifest)
HANDEMO_FUZZ_REPLAY_DECLARE(range)
HANDEMO_FUZZ_REPLAY_DECLARE(safetensors)

int main(int argc, char** argv)
{
    namespace fs = std::filesystem;
    const std::map<std::string, int (*)(const std::uint8_t*, std::size_t)> targets = {
        {"bvh", handemo_fuzz_replay_bvh},           {"checkpoint", handemo_fuzz_replay_checkpoint},
        {"csv", handemo_fuzz_replay_csv},           {"glove", handemo_fuzz_replay_glove},
        {"image", handemo_fuzz_replay_image},       {"manifest", handemo_fuzz_replay_manifest},
        {"range", handemo_fuzz_replay_range},       {"safetensors", handemo_fuzz_replay_safetensors}};
    if (argc < 3 || !targets.contains(argv[1])) {
        std::fprintf(stderr, "usage: handemo_fuzz_replay <target> <file or folder>...; targets:");
        for (const auto& [n, f] : targets) std::fprintf(stderr, " %s", n.c_str());
        std::fprintf(stderr, "\n");
        return 2;
    }
    const auto run = targets.at(argv[1]);
    std::vector<fs::path> files;
    bool optional = false;  // the next path may be missing (a target without regression files yet)
    for (int i = 2; i < argc; ++i) {
        if (std::string(argv[i]) == "--optional") {
            optional = true;
            continue;
        }
        const fs::path p = argv[i];
        if (!fs::exists(p) && std::exchange(optional, false)) continue;
        optional = false;
        if (fs::is_directory(p)) {
            for (const auto& e : fs::recursive_directory_iterator(p))
                if (e.is_regular_file() && e.path().filename().string().front() != '.') files.push_back(e.path());
        } else if (fs::is_regular_file(p)) {
            files.push_back(p);
        } else {
            std::fprintf(stderr, "handemo_fuzz_replay: %s: no such file or folder\n", p.c_str());
            return 1;
        }
    }
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
        const std::string bytes = handemo::read_file(f);
        std::fprintf(stderr, "%s\n", f.c_str());
        run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    }
    std::printf("handemo_fuzz_replay %s: %zu inputs, none escaped\n", argv[1], files.size());
    return files.empty() ? 1 : 0;
}
