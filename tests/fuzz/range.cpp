// Fuzz target: range.json (parse_range), then encoding a constant motion with an accepted range.
#include "fuzz.hpp"

#include <handemo/motion/codec.hpp>

namespace handemo_fuzz::range {

inline int run(const std::uint8_t* data, std::size_t size)
{
    return refuse_ok([&] {
        const handemo::angle_range r = handemo::parse_range(as_text(data, size), "fuzz-range.json");
        for (std::size_t c = 0; c < r.lo.size(); ++c) (void)r.contains(0.0, c);
        (void)handemo::encode_angle(0.0, r);
        (void)handemo::decode_angle(128.0, r);
    });
}

}  // namespace handemo_fuzz::range

HANDEMO_FUZZ_ENTRY(range)
