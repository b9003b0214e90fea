// Render module: pictures of motion made with no GPU and no external renderer. A software rasteriser
// (canvas, 5x7 font), skeleton figures and filmstrips as in the hand paper's Figures 4-12, one-row filmstrip
// animations (animation.hpp; handemo/gif.hpp writes them as animated GIF), enlarged motion images as in its
// Figure 3 (the Eq. 3 encoding, 9 keyframes x 23 joints), and SVG plots of training losses and evaluation
// results; and a self-contained HTML page that plays clips (viewer.hpp).
// Depends only on the core and motion headers (no stb): write the returned rgb_image with handemo/image.hpp
// (write_png) and the SVG and HTML text with write_file_atomic.
#pragma once

#include <handemo/render/animation.hpp>
#include <handemo/render/canvas.hpp>
#include <handemo/render/circumplex_strip.hpp>
#include <handemo/render/figure.hpp>
#include <handemo/render/filmstrip.hpp>
#include <handemo/render/font.hpp>
#include <handemo/render/motion_image.hpp>
#include <handemo/render/svg.hpp>
#include <handemo/render/viewer.hpp>
