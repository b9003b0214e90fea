# Bare-metal Cortex-M (a glove's microcontroller): Debian's gcc-arm-none-eabi with newlib-nano
# (`./setup.sh --cross`), hard float, no exceptions, no RTTI. HANDEMO_CORTEX_M_CPU picks the core:
#   cortex-m7         FPv5 double-precision FPU (-mfpu=fpv5-d16); the default
#   cortex-m55        Armv8.1-M with Helium: scalar FPU plus MVE integer and float (GCC 12's -mcpu=cortex-m55
#                     means +mve.fp+fp.dp; -mfpu=auto takes the FPU and MVE from -mcpu)
#   cortex-m55+nomve  the same core with the scalar FPU only, to see what MVE brings
# Used by tests/cross/cortex_m, whose firmware runs under qemu-system-arm with semihosting (mps2-an500 for the
# Cortex-M7, mps3-an547 for the Cortex-M55).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(HANDEMO_CORTEX_M_CPU cortex-m7 CACHE STRING "Cortex-M core: cortex-m7, cortex-m55 or cortex-m55+nomve")
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES HANDEMO_CORTEX_M_CPU)
if(HANDEMO_CORTEX_M_CPU STREQUAL "cortex-m7")
  set(HANDEMO_CORTEX_M_FLAGS "-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard")
elseif(HANDEMO_CORTEX_M_CPU MATCHES "^cortex-m55(\\+nomve)?$")
  set(HANDEMO_CORTEX_M_FLAGS "-mcpu=${HANDEMO_CORTEX_M_CPU} -mthumb -mfpu=auto -mfloat-abi=hard")
else()
  message(FATAL_ERROR "arm-none-eabi toolchain: HANDEMO_CORTEX_M_CPU '${HANDEMO_CORTEX_M_CPU}' is not cortex-m7, cortex-m55 or cortex-m55+nomve")
endif()
set(CMAKE_C_FLAGS_INIT "${HANDEMO_CORTEX_M_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT "${HANDEMO_CORTEX_M_FLAGS} -fno-exceptions -fno-rtti")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${HANDEMO_CORTEX_M_FLAGS} --specs=nano.specs -nostartfiles")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
