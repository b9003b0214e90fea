// Reset and exception vectors of the Cortex-M firmware: enable the FPU (and with it MVE on the Cortex-M55),
// copy .data, zero .bss, run static constructors, call main; SysTick counts its wraps (the instruction counter
// of main.cpp); a fault reports itself and exits non-zero.
#include "semihost.hpp"

#include <cstdint>

extern "C" {
extern std::uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
int main();
volatile std::uint32_t handemo_systick_wraps = 0;

[[noreturn]] void Reset_Handler()
{
    // CPACR: full access to CP10/CP11 (the FPU, and MVE on Armv8.1-M) before any floating-point or vector
    // instruction
    *reinterpret_cast<volatile std::uint32_t*>(0xE000ED88) |= 0xFu << 20;
    __asm__ volatile("dsb\n isb" ::: "memory");
    for (std::uint32_t *s = &_sidata, *d = &_sdata; d < &_edata;) *d++ = *s++;
    for (std::uint32_t* d = &_sbss; d < &_ebss;) *d++ = 0;
    for (auto f = __init_array_start; f < __init_array_end; ++f) (*f)();
    semihost::exit(main() == 0);
}

[[noreturn]] void Fault_Handler()
{
    semihost::write("cortex-m: fault\n");
    semihost::exit(false);
}

void SysTick_Handler() { handemo_systick_wraps = handemo_systick_wraps + 1; }

__attribute__((section(".isr_vector"), used)) const void* const vectors[16] = {
    &_estack,                                    // initial stack pointer
    reinterpret_cast<const void*>(&Reset_Handler),
    reinterpret_cast<const void*>(&Fault_Handler),  // NMI
    reinterpret_cast<const void*>(&Fault_Handler),  // HardFault
    reinterpret_cast<const void*>(&Fault_Handler),  // MemManage
    reinterpret_cast<const void*>(&Fault_Handler),  // BusFault
    reinterpret_cast<const void*>(&Fault_Handler),  // UsageFault
    reinterpret_cast<const void*>(&Fault_Handler),  // SecureFault (Armv8-M; reserved on the Cortex-M7)
    nullptr, nullptr, nullptr,
    reinterpret_cast<const void*>(&Fault_Handler),  // SVCall
    nullptr, nullptr,
    reinterpret_cast<const void*>(&Fault_Handler),  // PendSV
    reinterpret_cast<const void*>(&SysTick_Handler),
};
}
