// Fuzz target: safetensors files (parse_safetensors) and typed reads of every tensor.
#include "fuzz.hpp"

#include <handemo/nn/safetensors.hpp>

namespace handemo_fuzz::safetensors {

inline int run(const std::uint8_t* data, std::size_t size)
{
    return refuse_ok([&] {
        const handemo::safetensors_file f = handemo::parse_safetensors(as_text(data, size), "fuzz.safetensors");
        for (const auto& t : f.tensors) {
            (void)f.get<double>(t.name);
            (void)f.get<float>(t.name, t.shape);
            refuse_ok([&] { (void)f.get<std::uint64_t>(t.name); });
            refuse_ok([&] { (void)f.get<std::int64_t>(t.name); });
        }
        (void)handemo::serialize_safetensors(f);
    });
}

}  // namespace handemo_fuzz::safetensors

HANDEMO_FUZZ_ENTRY(safetensors)
