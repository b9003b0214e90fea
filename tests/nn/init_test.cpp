#include "test_model.hpp"

#include <doctest/doctest.h>
#include <handemo/nn/init.hpp>

#include <cmath>

using handemo::test::tiny_model;

namespace {

template <class T>
void check_uniform(const std::vector<T>& v, double bound)
{
    double mx = 0;
    for (T x : v) mx = std::max(mx, std::abs(static_cast<double>(x)));
    CHECK(mx <= bound);
    CHECK(mx > 0.7 * bound);  // n >= 27 draws: the largest |x| is near the bound
}

struct named_model {
    std::vector<std::string> names;
    std::vector<std::vector<std::size_t>> shapes;
    std::vector<std::vector<float>> values;
    template <class F>
    void for_each_parameter(F&& f)
    {
        for (std::size_t i = 0; i < names.size(); ++i)
            f(std::string_view(names[i]), std::span<float>(values[i]), std::span<float>(values[i]),
              std::span<const std::size_t>(shapes[i]));
    }
};

}  // namespace

TEST_CASE("init_pytorch_default applies PyTorch's rule to each kind of parameter")
{
    tiny_model<float> m;
    for (auto& p : m.params) std::fill(p.value.begin(), p.value.end(), 99.0f);
    handemo::init_pytorch_default(m, 1234);
    check_uniform(m.get("main.0.weight").value, 1.0 / std::sqrt(27.0));
    check_uniform(m.get("main.0.bias").value, 1.0 / std::sqrt(27.0));
    for (float x : m.get("main.1.weight").value) CHECK(x == 1.0f);
    for (float x : m.get("main.1.bias").value) CHECK(x == 0.0f);
    check_uniform(m.get("main.3.weight").value, 1.0 / std::sqrt(32.0));  // ConvTranspose: dim 1 x k x k
    check_uniform(m.get("head.weight").value, 1.0 / std::sqrt(10.0));
    for (float x : m.get("head.bias").value) CHECK(std::abs(x) <= 1.0 / std::sqrt(10.0));
    CHECK(handemo::pytorch_fan_in(std::vector<std::size_t>{16, 8, 4, 4}) == 128);
}

TEST_CASE("init_pytorch_default is deterministic per seed and draws one number per element")
{
    tiny_model<double> a, b, c;
    handemo::init_pytorch_default(a, 7);
    handemo::init_pytorch_default(b, 7);
    handemo::init_pytorch_default(c, 8);
    for (std::size_t i = 0; i < a.params.size(); ++i) CHECK(a.params[i].value == b.params[i].value);
    CHECK(a.params[0].value != c.params[0].value);
    // The first weight element is the first draw of rng(7) mapped to U(-b, b).
    handemo::rng r(7);
    const double bound = 1.0 / std::sqrt(27.0);
    CHECK(a.params[0].value[0] == r.uniform(-bound, bound));
    // float and double models draw the same numbers (rounded)
    tiny_model<float> f;
    handemo::init_pytorch_default(f, 7);
    CHECK(f.params[0].value[5] == static_cast<float>(a.params[0].value[5]));
}

TEST_CASE("init_pytorch_default statistics match U(-1/sqrt(fan_in), 1/sqrt(fan_in))")
{
    named_model m{{"conv.weight"}, {{64, 32, 4, 4}}, {std::vector<float>(64 * 32 * 16)}};
    handemo::init_pytorch_default(m, 3);
    double s = 0, s2 = 0;
    for (float x : m.values[0]) {
        s += x;
        s2 += double(x) * x;
    }
    const double n = static_cast<double>(m.values[0].size());
    CHECK(std::abs(s / n) < 0.002);
    CHECK(s2 / n == doctest::Approx(1.0 / (3.0 * 512.0)).epsilon(0.03));  // Var U(-b,b) = b^2/3
}

TEST_CASE("init_pytorch_default rejects parameters whose kind it cannot decide")
{
    named_model unknown{{"main.0.scale"}, {{3}}, {std::vector<float>(3)}};
    CHECK_THROWS_WITH_AS(handemo::init_pytorch_default(unknown, 1), doctest::Contains("main.0.scale"),
                         handemo::value_error);
    named_model orphan{{"head.bias"}, {{3}}, {std::vector<float>(3)}};
    CHECK_THROWS_WITH_AS(handemo::init_pytorch_default(orphan, 1), doctest::Contains("head.bias"),
                         handemo::value_error);
    named_model scalar{{"w.weight"}, {{}}, {std::vector<float>(1)}};
    CHECK_THROWS_AS(handemo::init_pytorch_default(scalar, 1), handemo::value_error);
}
