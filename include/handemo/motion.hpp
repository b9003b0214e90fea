// Motion module: skeletons, clips, forward kinematics, formats (BVH, CSV), keyframes and the
// image codec of the hand paper (Eq. 3 and Eq. 6), the synthetic hand dataset, and the circumplex coordinates of
// emotion labels with the interpolation between them.
#pragma once

#include <handemo/motion/skeleton.hpp>
#include <handemo/motion/clip.hpp>
#include <handemo/motion/bvh.hpp>
#include <handemo/motion/csv.hpp>
#include <handemo/motion/hand.hpp>
#include <handemo/motion/body.hpp>
#include <handemo/motion/keyframes.hpp>
#include <handemo/motion/codec.hpp>
#include <handemo/motion/synth.hpp>
#include <handemo/motion/detail_layer.hpp>
#include <handemo/motion/circumplex.hpp>
