// handemo's StarGAN in float against PyTorch in double (relative 1e-4 of each tensor's scale).
#include "golden_stargan.hpp"

using handemo::test::golden::suite;
using handemo::test::golden::tolerance;

namespace {
// float: error relative to the tensor's largest magnitude (instance norm over 3x6 maps amplifies the
// rounding of single elements; per element the worst seen is ~5e-4 of a value 100x below the scale)
constexpr tolerance tol{1e-4, 1.0};
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
