// ARM semihosting for the Cortex-M firmware (QEMU -semihosting): text out through the debugger (SYS_WRITE0)
// and exit with a status (SYS_EXIT). No libc stdio, so nothing allocates.
#pragma once

#include <cstdint>

namespace semihost {

inline int call(int op, const void* arg) noexcept
{
    register int r0 __asm__("r0") = op;
    register const void* r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

inline void write(const char* s) noexcept { call(0x04, s); }  // SYS_WRITE0

inline void write(std::uint64_t v) noexcept
{
    char buf[24];
    char* p = buf + sizeof buf - 1;
    *p = 0;
    do {
        *--p = char('0' + v % 10);
        v /= 10;
    } while (v);
    write(p);
}

/// SYS_EXIT: ADP_Stopped_ApplicationExit (QEMU exits 0) or ADP_Stopped_RunTimeErrorUnknown (QEMU exits 1).
[[noreturn]] inline void exit(bool ok) noexcept
{
    call(0x18, reinterpret_cast<const void*>(ok ? 0x20026 : 0x20023));
    for (;;) {
    }
}

}  // namespace semihost
