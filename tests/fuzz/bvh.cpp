// Fuzz target: BVH text (parse_bvh), then the writer and a second read of what was accepted.
#include "fuzz.hpp"

#include <handemo/motion/bvh.hpp>

namespace handemo_fuzz::bvh {

inline int run(const std::uint8_t* data, std::size_t size)
{
    return refuse_ok([&] {
        const handemo::clip c = handemo::parse_bvh(as_text(data, size), "fuzz.bvh");
        c.validate("fuzz.bvh");
        // what was accepted must write and read back
        (void)handemo::parse_bvh(handemo::to_bvh_string(c), "fuzz-roundtrip.bvh");
    });
}

}  // namespace handemo_fuzz::bvh

HANDEMO_FUZZ_ENTRY(bvh)
