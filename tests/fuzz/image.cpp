// Fuzz target: BMP and PNG files (decode_image, stb_image behind handemo's own header, CRC and zlib checks).
#include "fuzz.hpp"

#include <handemo/image/io.hpp>

namespace handemo_fuzz::image {

inline int run(const std::uint8_t* data, std::size_t size)
{
    return refuse_ok([&] {
        const handemo::rgb_image im = handemo::decode_image(as_text(data, size), "fuzz.img");
        im.validate("fuzz.img");
    });
}

}  // namespace handemo_fuzz::image

HANDEMO_FUZZ_ENTRY(image)
