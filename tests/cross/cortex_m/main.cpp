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
    return ok ? 0 : 1;
}
