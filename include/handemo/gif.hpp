// GIF module (optional, target handemo::gif, links Debian's giflib): animated GIFs of filmstrip animations
// (render/animation.hpp), so a README or a chat can show motion moving. A quantised global palette
// (gif/palette.hpp, no giflib) and the encoder (gif/writer.hpp, the one file that includes <gif_lib.h>).
// Kept out of <handemo.hpp> so the core include path never drags in giflib.
#pragma once

#include <handemo/gif/palette.hpp>
#include <handemo/gif/writer.hpp>
