// Replays fuzz corpora and regression files through the harnesses' plain entry points (no libFuzzer), so
// CTest (label fuzz-replay) runs them under ASan/UBSan with any compiler that has the sanitizers (GCC too).
// Usage: handemo_fuzz_replay <target> [--optional] <file or folder>...   (folders are walked recursively, sorted;
// a path after --optional may be missing)
// Exit 0 when every input is accepted or refused with a handemo error; anything else aborts.
#define HANDEMO_FUZZ_REPLAY 1
#include "bvh.cpp"
#include "checkpoint.cpp"
#include "csv.cpp"
#include "glove.cpp"
#include "image.cpp"
#include "manifest.cpp"
#include "range.cpp"
#include "safetensors.cpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <utility>
#include <vector>

int main(int argc, char** argv)
{
    namespace fs = std::filesystem;
    const std::map<std::string, int (*)(const std::uint8_t*, std::size_t)> targets = {
        {"bvh", handemo_fuzz::bvh::run},           {"checkpoint", handemo_fuzz::checkpoint::run},
        {"csv", handemo_fuzz::csv::run},           {"glove", handemo_fuzz::glove::run},
        {"image", handemo_fuzz::image::run},       {"manifest", handemo_fuzz::manifest::run},
        {"range", handemo_fuzz::range::run},       {"safetensors", handemo_fuzz::safetensors::run}};
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
