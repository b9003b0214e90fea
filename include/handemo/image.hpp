// Image module (optional, target handemo::image, links Debian's libstb): the in-memory RGB image that
// holds the motion images of Eq. 3 / Eq. 6 of Chan, Irimia, Ho 2020, and lossless BMP/PNG file I/O.
// Kept out of <handemo.hpp> so the core include path never drags in stb.
#pragma once

#include <handemo/image/rgb_image.hpp>
#include <handemo/image/io.hpp>
