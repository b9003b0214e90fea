// handemo's StarGAN in double against PyTorch in double: agreement to rounding, within 1e-12 relative
// (floored at 1% of each tensor's largest magnitude; the README's bound). Measured worst: 5.1e-13 (a G
// weight gradient through L_G, on an AVX-512 machine), 5e-13 on another.
#include "golden_stargan.hpp"

using handemo::test::golden::suite;
using handemo::test::golden::tolerance;

namespace {
constexpr tolerance tol{1e-12, 1e-2};
}

TEST_CASE("tiny StarGAN (double): PyTorch weights load by name; G, G::infer and D forward match PyTorch")
{
    suite<double>::forward(tol);
}
TEST_CASE("tiny StarGAN (double): gradient penalty and its gradient w.r.t. D (double backward) match PyTorch")
{
    suite<double>::gradient_penalty(tol);
}
TEST_CASE("tiny StarGAN (double): L_D and its gradient w.r.t. D match PyTorch") { suite<double>::loss_d(tol); }
TEST_CASE("tiny StarGAN (double): L_G and its gradient w.r.t. G match PyTorch") { suite<double>::loss_g(tol); }
