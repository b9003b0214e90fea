// Forwarding header: the motion image as an rgb_image (to_image / from_image) moved to
// <handemo/image/keyframe_image.hpp>, next to image I/O, because it needs stb (target handemo::image) and
// the motion module does not. This header keeps the old path working; new code includes the image one.
#pragma once

#include <handemo/image/keyframe_image.hpp>
