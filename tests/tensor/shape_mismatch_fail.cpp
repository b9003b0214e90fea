// Must NOT compile: adding library tensors (handemo::operator+ of handemo/tensor.hpp) or autodiff
// variables (handemo::autodiff::operator+) of different shapes. The CTest tests tensor_shape_mismatch_*
// compile this file, expect failure and grep the diagnostic for the message naming both shapes.
// Selected by -DHANDEMO_MISMATCH=1 (tensor) or 2 (autodiff var). With -DHANDEMO_SAME_SHAPE the shapes
// agree and the file must compile (tensor_shape_match_*: the failure above is the shape check's, not a
// broken file's).
#include <cstddef>
#ifdef HANDEMO_SAME_SHAPE
constexpr std::size_t last = 24;
#else
constexpr std::size_t last = 23;
#endif
#if HANDEMO_MISMATCH == 1
#include <handemo/tensor.hpp>
int main()
{
    handemo::tensor<float, 16, 3, 12, 24> a;
    handemo::tensor<float, 16, 3, 12, last> b;
    auto c = a + b;
    (void)c;
}
#else
#include <handemo/autodiff/ops.hpp>
int main()
{
    handemo::autodiff::tape<float> t;
    auto a = t.constant<handemo::shape<16, 3, 12, 24>>(1.f);
    auto b = t.constant<handemo::shape<16, 3, 12, last>>(1.f);
    auto c = a + b;
    (void)c;
}
#endif
