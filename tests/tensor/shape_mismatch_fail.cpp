// Must NOT compile: adding autodiff variables (and tensors) of different shapes. The CTest test
// tensor_shape_mismatch compiles this file, expects failure and greps the diagnostic for the message
// naming both shapes. Selected by -DHANDEMO_MISMATCH=1 (tensor) or 2 (autodiff var).
#if HANDEMO_MISMATCH == 1
#include <handemo/tensor/tensor.hpp>
#include <handemo/tensor/shape.hpp>
template <class T, std::size_t... A, std::size_t... B>
void add_tensors(const handemo::tensor<T, A...>&, const handemo::tensor<T, B...>&)
{
    handemo::require_same_shape<"add", handemo::shape<A...>, handemo::shape<B...>>();
}
int main()
{
    handemo::tensor<float, 16, 3, 12, 24> a;
    handemo::tensor<float, 16, 3, 12, 23> b;
    add_tensors(a, b);
}
#else
#include <handemo/autodiff/ops.hpp>
int main()
{
    handemo::autodiff::tape<float> t;
    auto a = t.constant<handemo::shape<16, 3, 12, 24>>(1.f);
    auto b = t.constant<handemo::shape<16, 3, 12, 23>>(1.f);
    auto c = a + b;
    (void)c;
}
#endif
