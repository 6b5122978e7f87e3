// The minimal start-up of the firmware example on QEMU's mps2-an386 (Cortex-M4F): a vector table with
// the initial stack pointer and the reset handler, which copies .data, zeroes .bss, turns the FPU on,
// runs the static constructors and calls the program (embedded::programMain, platform.hpp). Every other exception ends
// the program through semihosting with a failure (a fault is a failed run, never a hang).

#include <cstdint>

#include "platform.hpp"

extern "C" {
extern std::uint32_t __data_start[], __data_end[], __data_load[], __bss_start[], __bss_end[], __stack_top[];
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
[[noreturn]] void resetHandler();
}

namespace {

[[noreturn]] void faultHandler() {
  embedded::writeText("fault: an exception other than reset was taken\n");
  embedded::exitProgram(3);
}

}  // namespace

extern "C" [[noreturn]] void resetHandler() {
  for (std::uint32_t *from = __data_load, *to = __data_start; to < __data_end;) *to++ = *from++;
  for (std::uint32_t* p = __bss_start; p < __bss_end;) *p++ = 0;
  // CPACR: full access to CP10 and CP11, the FPU (off at reset); the barriers make the next
  // instruction see it.
  volatile std::uint32_t& cpacr = *reinterpret_cast<volatile std::uint32_t*>(0xE000ED88u);
  cpacr = cpacr | (0xFu << 20);
  asm volatile("dsb\n\tisb" ::: "memory");
  for (void (**init)() = __init_array_start; init < __init_array_end; ++init) (*init)();
  embedded::exitProgram(embedded::programMain());
}

// Initial SP, reset, then NMI … SysTick (14 system exceptions): all faults end the run.
using Vector = void (*)();
extern "C" __attribute__((section(".vectors"), used))
const Vector vectorTable[16] = {reinterpret_cast<Vector>(__stack_top),
                                resetHandler,
                                faultHandler,
                                faultHandler,
                                faultHandler,
                                faultHandler,
                                faultHandler,
                                nullptr,
                                nullptr,
                                nullptr,
                                nullptr,
                                faultHandler,
                                faultHandler,
                                nullptr,
                                faultHandler,
                                faultHandler};
