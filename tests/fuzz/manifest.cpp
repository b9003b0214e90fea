// Fuzz target: manifest.csv of a data folder (parse_manifest); every accepted path stays inside the folder.
#include "fuzz.hpp"

#include <handemo/stargan/dataset.hpp>

#include <cstdlib>

namespace handemo_fuzz::manifest {

inline int run(const std::uint8_t* data, std::size_t size)
{
    return refuse_ok([&] {
        const std::filesystem::path dir = "data";
        const auto clips = handemo::stargan::parse_manifest(as_text(data, size), dir, "data/manifest.csv");
        for (const auto& c : clips) {
            const auto rel = c.path.lexically_relative(dir).lexically_normal();
            if (rel.empty() || rel.is_absolute() || *rel.begin() == "..") std::abort();  // escaped the folder
        }
    });
}

}  // namespace handemo_fuzz::manifest

HANDEMO_FUZZ_ENTRY(manifest)
