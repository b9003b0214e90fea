// handemo's StarGAN in float against PyTorch in double: within 7.6e-6 of each tensor's scale (the README's bound).
#include "golden_stargan.hpp"

using handemo::test::golden::suite;
using handemo::test::golden::tolerance;

namespace {
// float: error relative to the tensor's largest magnitude. Measured worst: 6.7e-6 (L_G's gradient of a G
// bias, on an AVX-512 machine), 7.6e-6 on another; the double model matches PyTorch to ~5e-13, so the formulas are exact
// and this is float precision.
constexpr tolerance tol{7.6e-6, 1.0};
}  // namespace

TEST_CASE("tiny StarGAN (float): PyTorch weights load by name; G, G::infer and D forward match PyTorch")
{
    suite<float>::forward(tol);
}
TEST_CASE("tiny StarGAN (float): gradient penalty and its gradient w.r.t. D (double backward) match PyTorch")
{
    suite<float>::gradient_penalty(tol);
}
TEST_CASE("tiny StarGAN (float): L_D and its gradient w.r.t. D match PyTorch") { suite<float>::loss_d(tol); }
TEST_CASE("tiny StarGAN (float): L_G and its gradient w.r.t. G match PyTorch") { suite<float>::loss_g(tol); }
