#include "fixture.hpp"
#include "test_model.hpp"

#include <doctest/doctest.h>
#include <handemo/nn/adam.hpp>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>

// Counts heap allocations so that the test can prove adam::step allocates nothing after construction.
// (Replacing the global operator new is allowed once per program; no other nn test does it.)
namespace {
std::atomic<long> allocations{0};
}
void* operator new(std::size_t n)
{
    ++allocations;
    if (void* p = std::malloc(n ? n : 1)) return p;
    throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

using handemo::test::fixture;
using handemo::test::max_rel_error;

namespace {

template <class T>
void run_adam_golden(const char* dt, double tol)
{
    const auto& f = fixture("adam.safetensors");
    const std::string p = dt;
    std::vector<T> param = f.get<T>(p + ".p0");
    const std::vector<double> lrs = f.get<double>(p + ".lr");
    const std::size_t sizes[] = {param.size()};
    handemo::adam<T> opt(sizes, {0.5, 0.999, 1e-8});
    for (std::size_t k = 1; k <= lrs.size(); ++k) {
        const std::vector<T> g = f.get<T>(p + ".g" + std::to_string(k));
        opt.step_tensor(0, param, g, lrs[k - 1]);
        const std::vector<T> want = f.get<T>(p + ".p" + std::to_string(k));
        INFO(dt << " step " << k);
        CHECK(max_rel_error(param, want, 1e-6) < tol);
    }
    CHECK(max_rel_error(opt.m(), f.get<T>(p + ".m"), 1e-6) < tol);
    CHECK(max_rel_error(opt.v(), f.get<T>(p + ".v"), 1e-12) < tol);
    CHECK(opt.steps()[0] == static_cast<std::int64_t>(lrs.size()));
}

}  // namespace

TEST_CASE("adam matches torch.optim.Adam step by step (golden fixture)")
{
    run_adam_golden<float>("F32", 1e-5);
    run_adam_golden<double>("F64", 1e-12);
}

TEST_CASE("adam over a model: same result as per-tensor steps, state exposed and restorable")
{
    handemo::test::tiny_model<float> a, b;
    for (std::size_t i = 0; i < a.params.size(); ++i)
        for (std::size_t j = 0; j < a.params[i].value.size(); ++j) {
            a.params[i].value[j] = b.params[i].value[j] = std::sin(float(i * 100 + j));
            a.params[i].grad[j] = b.params[i].grad[j] = std::cos(float(i * 37 + j * 3));
        }
    handemo::adam<float> oa(a, {0.5, 0.999, 1e-8});
    CHECK(oa.tensor_count() == a.params.size());
    CHECK(oa.names()[2] == "main.1.weight");
    oa.step(a, 1e-3);
    oa.step(a, 1e-3);
    // b: two steps, but the state is saved after the first and loaded into a fresh optimiser
    handemo::adam<float> ob(b, {0.5, 0.999, 1e-8});
    ob.step(b, 1e-3);
    std::vector<float> m(ob.m().begin(), ob.m().end()), v(ob.v().begin(), ob.v().end());
    std::vector<std::int64_t> s(ob.steps().begin(), ob.steps().end());
    handemo::adam<float> oc(b, {0.5, 0.999, 1e-8});
    std::copy(m.begin(), m.end(), oc.m().begin());
    std::copy(v.begin(), v.end(), oc.v().begin());
    std::copy(s.begin(), s.end(), oc.steps().begin());
    oc.step(b, 1e-3);
    for (std::size_t i = 0; i < a.params.size(); ++i) CHECK(a.params[i].value == b.params[i].value);
    // first step of Adam moves every element by ~lr against the gradient's sign (m_hat/sqrt(v_hat) = sign g)
    handemo::test::tiny_model<double> c;
    for (auto& prm : c.params)
        for (std::size_t j = 0; j < prm.value.size(); ++j) prm.grad[j] = (j % 2 ? 1.0 : -1.0) * (1.0 + double(j));
    handemo::adam<double> od(c);
    od.step(c, 0.01);
    for (auto& prm : c.params)
        for (std::size_t j = 0; j < prm.value.size(); ++j)
            CHECK(prm.value[j] == doctest::Approx(j % 2 ? -0.01 : 0.01).epsilon(1e-6));
}

TEST_CASE("adam split over a thread pool: the same bits as on one thread")
{
    // a long tensor (split in parts cut at multiples of 16, the last with the SIMD loop's scalar tail)
    const std::size_t n = 100003;
    const std::size_t sizes[] = {n, 7};
    std::vector<float> pa(n), pb, ga(n), qa(7, 0.5f), qb(7, 0.5f), gq(7, -0.25f);
    for (std::size_t j = 0; j < n; ++j) pa[j] = std::sin(float(j)), ga[j] = std::cos(float(j) * 0.37f);
    pb = pa;
    handemo::adam<float> oa(sizes, {0.5, 0.999, 1e-8}), ob(sizes, {0.5, 0.999, 1e-8});
    handemo::thread_pool pool(3);
    for (int k = 0; k < 3; ++k) {
        oa.step_tensor(0, pa, ga, 1e-3);
        ob.step_tensor(0, pb, ga, 1e-3, &pool);
        oa.step_tensor(1, qa, gq, 1e-3);
        ob.step_tensor(1, qb, gq, 1e-3, &pool);
    }
    CHECK(pa == pb);
    CHECK(qa == qb);
    CHECK(std::equal(oa.m().begin(), oa.m().end(), ob.m().begin()));
    CHECK(std::equal(oa.v().begin(), oa.v().end(), ob.v().begin()));
    CHECK(pa != std::vector<float>(n, 0.f));
}

TEST_CASE("adam::step allocates nothing after construction")
{
    handemo::test::tiny_model<float> a;
    for (auto& p : a.params) std::fill(p.grad.begin(), p.grad.end(), 0.1f);
    handemo::adam<float> opt(a);
    const handemo::lr_schedule sched{1e-3, 100, 0.5};
    const long before = allocations.load();
    for (std::int64_t k = 0; k < 100; ++k) opt.step(a, sched(k));
    CHECK(allocations.load() == before);
    CHECK(opt.steps()[0] == 100);
}

TEST_CASE("adam rejects a model whose parameter list changed, and bad options")
{
    handemo::test::tiny_model<float> a;
    handemo::adam<float> opt(a);
    handemo::test::tiny_model<float> b;
    b.params[3].name = "main.1.beta";
    CHECK_THROWS_WITH_AS(opt.step(b, 1e-3), doctest::Contains("main.1.beta"), handemo::shape_error);
    b.params.pop_back();
    b.params[3].name = "main.1.bias";
    CHECK_THROWS_WITH_AS(opt.step(b, 1e-3), doctest::Contains("expected 7"), handemo::shape_error);
    std::vector<float> p(3), g(4);
    CHECK_THROWS_AS(opt.step_tensor(0, p, g, 1e-3), handemo::shape_error);
    CHECK_THROWS_AS(opt.step_tensor(99, p, g, 1e-3), handemo::shape_error);
    CHECK_THROWS_AS(handemo::adam<float>(a, {1.0, 0.999, 1e-8}), handemo::value_error);
}

TEST_CASE("lr_schedule: constant, then linear to 0 over the last part")
{
    const handemo::lr_schedule s{1e-4, 200000, 0.5};
    s.validate();
    CHECK(s.decay_begin() == 100000);
    CHECK(s(0) == 1e-4);
    CHECK(s(99999) == 1e-4);
    CHECK(s(100000) == doctest::Approx(1e-4));
    CHECK(s(150000) == doctest::Approx(0.5e-4));
    CHECK(s(199999) == doctest::Approx(1e-4 / 100000));
    CHECK(s(200000) == 0.0);
    CHECK(s(300000) == 0.0);
    double prev = 1.0;
    for (std::int64_t k = 0; k <= 200000; k += 997) {
        CHECK(s(k) <= prev);
        prev = s(k);
    }
    const handemo::lr_schedule constant{2e-4, 10, 1.0};
    CHECK(constant(9) == 2e-4);
    CHECK_THROWS_AS((handemo::lr_schedule{1e-4, 0, 0.5}.validate()), handemo::value_error);
    CHECK_THROWS_AS((handemo::lr_schedule{1e-4, 10, 1.5}.validate()), handemo::value_error);
    CHECK_THROWS_AS((handemo::lr_schedule{-1.0, 10, 0.5}.validate()), handemo::value_error);
}
