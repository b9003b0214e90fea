// The circumplex (RCM) module: continuous emotion control of Aristidou et al. 2017, "Emotion control of
// unstructured dance movements". Analysis (Section 3): joint roles, LMA features (Table 1), effective and
// consistent feature selection, PCA, RBF maps features <-> (valence, arousal) (Eq. 1-4), pose clustering
// (Eq. 5), label coordinates on the circumplex, the model file. Needs the target handemo::rcm
// (xtensor-blas, LAPACK); the core umbrella <handemo.hpp> does not include it.
#pragma once

#include <handemo/rcm/roles.hpp>
#include <handemo/rcm/lma.hpp>
#include <handemo/rcm/selection.hpp>
#include <handemo/rcm/maps.hpp>
#include <handemo/rcm/cluster.hpp>
#include <handemo/rcm/circumplex.hpp>
#include <handemo/rcm/model.hpp>
// Synthesis (Section 4): the rules of Table 2 on the autodiff tape, differentiable features, the Eq. 6
// objective optimised jointly, damped least-squares IK, spline back to full rate.
#include <handemo/rcm/ik.hpp>
#include <handemo/rcm/rules.hpp>
#include <handemo/rcm/features_ad.hpp>
#include <handemo/rcm/synth.hpp>
// A fitted model driving the synthesis: a motion to any circumplex point, or along a path of points.
#include <handemo/rcm/control.hpp>
