# Bare-metal Cortex-M7 (a glove's microcontroller): Debian's gcc-arm-none-eabi with newlib-nano
# (`./setup.sh --cross`), hard float on the FPv5 double-precision unit, no exceptions, no RTTI.
# Used by tests/cross/cortex_m, whose firmware runs under qemu-system-arm -M mps2-an500 with semihosting.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(HANDEMO_CORTEX_M_FLAGS "-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard")
set(CMAKE_C_FLAGS_INIT "${HANDEMO_CORTEX_M_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT "${HANDEMO_CORTEX_M_FLAGS} -fno-exceptions -fno-rtti")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${HANDEMO_CORTEX_M_FLAGS} --specs=nano.specs -nostartfiles")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
