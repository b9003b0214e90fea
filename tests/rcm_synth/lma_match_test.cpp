// The differentiable features equal lma.hpp's basic features (the analysis side's double-precision
// definitions) on every frame: a synthetic body and a synthetic hand.
#include "lma_match.hpp"

using namespace handemo;

TEST_CASE("rcm features: the differentiable body features equal lma.hpp's f1-f14, f16-f27, f29 on every frame")
{
    CHECK(test::check_against_lma(test::humanoid_dance(90)) == 27);
}

TEST_CASE("rcm features: the differentiable hand features equal lma.hpp's h1-h25 on every frame")
{
    CHECK(test::check_against_lma(synthesize(hand_motion::crawling, emotion::fearful, 1, 9, 30.0)) == 25);
}
