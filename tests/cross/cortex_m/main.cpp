// The Cortex-M firmware (a Cortex-M7 or a Cortex-M55: HANDEMO_CORTEX_M_CPU): runs handemo::micro::generator on
// the self-test of a header written by `handemo export --header` (weights in flash, activations in static RAM,
// no heap), checks the output against the host's (x86) within 1e-5, and counts the instructions of one
// inference. Under `qemu-system-arm -icount shift=0` virtual time advances by one step per instruction, so
// SysTick (clocked by the CPU clock) counts instructions in units of a fixed number of instructions per tick,
// calibrated on a loop of known length.
#include HANDEMO_MODEL_HEADER
#include <handemo/micro.hpp>

#include "semihost.hpp"

#include <cmath>
#include <cstdint>

extern "C" volatile std::uint32_t handemo_systick_wraps;

namespace {

using model = handemo_model::model;
using gen = handemo::micro::generator<model>;

gen::workspace ws;
float out[3 * gen::K * gen::J];

volatile std::uint32_t& syst(std::uintptr_t a) { return *reinterpret_cast<volatile std::uint32_t*>(a); }

void systick_start()
{
    syst(0xE000E014) = 0xFFFFFF;  // SYST_RVR: 24-bit period
    syst(0xE000E018) = 0;         // SYST_CVR
    syst(0xE000E010) = 7;         // SYST_CSR: CPU clock, interrupt on wrap, enable
}

/// Ticks since systick_start (wraps counted by SysTick_Handler; re-read if one happened meanwhile).
std::uint64_t ticks()
{
    for (;;) {
        const std::uint32_t w = handemo_systick_wraps, v = syst(0xE000E018);
        if (w == handemo_systick_wraps) return (std::uint64_t(w) << 24) + (0xFFFFFFu - v);
    }
}

/// Exactly 2 n + 1 instructions.
void spin(std::uint32_t n)
{
    __asm__ volatile("1: subs %0, %0, #1\n bne 1b" : "+r"(n)::"cc");
}

#if HANDEMO_MICRO_MVE && !defined(HANDEMO_FIRMWARE_NO_MVE_CHECK)
// The MVE convolutions (micro::detail::mve) against the plain ones (micro::detail, which test_micro checks
// against the reference kernels) on the generator's layers and on geometries it does not use: tiles of 1 to
// 8 pixels (a predicated part of 1 to 3 lanes), gathers of stride 2 and 3, the transposed fallback.
float cx[4608], cw[9216], cy_plain[4608], cy_mve[4608], cpad[4608];
std::uint32_t lcg = 12345;

float uniform()
{
    lcg = lcg * 1664525u + 1013904223u;
    return float(lcg >> 8) / 8388608.f - 1.f;
}

/// max |mve - plain| / max |plain| of convolution G (transposed when T) on uniform(-1, 1) data.
template <handemo::kernels::conv_geometry G, bool T>
float mve_error()
{
    namespace d = handemo::micro::detail;
    constexpr std::size_t nx = T ? G.y_size() : G.x_size(), ny = T ? G.x_size() : G.y_size();
    static_assert(nx <= 4608 && ny <= 4608 && G.w_size() <= 9216 && d::conv_pad_elements(G) <= 4608 &&
                  (!T || d::convt_pad_elements(G) <= 4608), "mve_error: the geometry does not fit the buffers");
    for (std::size_t i = 0; i < nx; ++i) cx[i] = uniform();
    for (std::size_t i = 0; i < G.w_size(); ++i) cw[i] = uniform();
    for (std::size_t i = 0; i < ny; ++i) cy_plain[i] = cy_mve[i] = 1e9f;
    if constexpr (T) {
        d::conv_transpose<G>(cx, cw, cy_plain, cpad);
        d::mve::conv_transpose<G>(cx, cw, cy_mve, cpad);
    } else {
        d::conv_forward<G>(cx, cw, cy_plain, cpad);
        d::mve::conv_forward<G>(cx, cw, cy_mve, cpad);
    }
    float worst = 0.f, scale = 0.f;
    for (std::size_t i = 0; i < ny; ++i) {
        worst = std::fmax(worst, std::fabs(cy_mve[i] - cy_plain[i]));
        scale = std::fmax(scale, std::fabs(cy_plain[i]));
    }
    return scale > 0.1f ? worst / scale : 1.f;
}

float mve_errors()
{
    using handemo::kernels::conv_geometry;
    const float e[] = {
        mve_error<conv_geometry{1, 8, 12, 24, 8, 7, 7, 1, 3}, false>(),
        mve_error<conv_geometry{1, 8, 12, 24, 16, 4, 4, 2, 1}, false>(),
        mve_error<conv_geometry{1, 32, 3, 6, 32, 3, 3, 1, 1}, false>(),
        mve_error<conv_geometry{1, 8, 12, 24, 3, 7, 7, 1, 3}, false>(),
        mve_error<conv_geometry{1, 3, 5, 11, 4, 3, 3, 1, 1}, false>(),
        mve_error<conv_geometry{1, 2, 9, 15, 3, 3, 3, 2, 1}, false>(),
        mve_error<conv_geometry{1, 3, 6, 9, 2, 2, 3, 1, 0}, false>(),
        mve_error<conv_geometry{1, 2, 7, 14, 5, 5, 1, 1, 2}, false>(),
        mve_error<conv_geometry{1, 3, 9, 18, 2, 3, 3, 3, 1}, false>(),
        mve_error<conv_geometry{1, 16, 6, 12, 32, 4, 4, 2, 1}, true>(),
        mve_error<conv_geometry{1, 8, 12, 24, 16, 4, 4, 2, 1}, true>(),
        mve_error<conv_geometry{1, 3, 10, 8, 4, 3, 3, 2, 1}, true>(),
        mve_error<conv_geometry{1, 2, 9, 12, 3, 3, 3, 3, 0}, true>(),
        mve_error<conv_geometry{1, 4, 8, 16, 2, 4, 2, 2, 0}, true>(),
    };
    float worst = 0.f;
    for (float v : e) worst = std::fmax(worst, v);
    return worst;
}
#endif

}  // namespace

int main()
{
    systick_start();
    spin(1000);  // past SysTick's first reload from RVR (the counter reads 0 until then)
    constexpr std::uint32_t n = 2000000;
    const std::uint64_t c0 = ticks();
    spin(n);
    const std::uint64_t c1 = ticks();
    const std::uint64_t t0 = ticks();
    gen::infer(model::self_test_input, model::self_test_target, out, ws);
    const std::uint64_t t1 = ticks();
    float worst = 0.f;
    for (std::size_t i = 0; i < 3 * gen::K * gen::J; ++i) worst = std::fmax(worst, std::fabs(out[i] - model::self_test_output[i]));
    const bool ok = worst <= 1e-5f;
    // instructions = ticks x (2n+1) / calibration ticks, rounded
    const std::uint64_t cal = c1 - c0, inf = t1 - t0;
    const std::uint64_t insns = (inf * (2ull * n + 1) + cal / 2) / cal;
    semihost::write(HANDEMO_CORTEX_M_CPU " ");
    semihost::write(model::config);
    semihost::write(" self-test target ");
    semihost::write(model::domain_names[model::self_test_target]);
    semihost::write(": max |device - host| = ");
    semihost::write(std::uint64_t(worst * 1e9f));
    semihost::write(ok ? " e-9: ok\n" : " e-9: FAILED\n");
    semihost::write("instructions per inference: ");
    semihost::write(insns);
    semihost::write(" (SysTick ");
    semihost::write(inf);
    semihost::write(" ticks; calibration ");
    semihost::write(cal);
    semihost::write(" ticks for ");
    semihost::write(2ull * n + 1);
    semihost::write(" instructions)\n");
#if HANDEMO_MICRO_MVE && !defined(HANDEMO_FIRMWARE_NO_MVE_CHECK)
    const float mve = mve_errors();
    const bool mve_ok = mve <= 1e-6f;
    semihost::write("MVE convolutions against the plain ones (14 geometries): max relative difference ");
    semihost::write(std::uint64_t(mve * 1e9f));
    semihost::write(mve_ok ? " e-9: ok\n" : " e-9: FAILED\n");
    return ok && mve_ok ? 0 : 1;
#else
    return ok ? 0 : 1;
#endif
}
