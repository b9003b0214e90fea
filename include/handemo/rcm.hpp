// The circumplex module (Aristidou et al. 2017, "Emotion control of unstructured dance movements"):
// synthesis by the rules of Table 2 with all coefficients optimised jointly through the autodiff tape, a
// damped least-squares IK and spline interpolation back to full rate (Section 4). Target handemo::rcm.
#pragma once

#include <handemo/rcm/detail/ops.hpp>
#include <handemo/rcm/ik.hpp>
#include <handemo/rcm/rules.hpp>
#include <handemo/rcm/features_ad.hpp>
#include <handemo/rcm/synth.hpp>
