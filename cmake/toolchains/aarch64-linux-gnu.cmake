# Cross toolchain for 64-bit ARM Linux (a VR headset, a Raspberry Pi 4/5): Debian's g++-aarch64-linux-gnu
# (`./setup.sh --cross`). Programs run on this machine under qemu-aarch64 (Debian qemu-user) with the
# target's libraries from /usr/aarch64-linux-gnu, so `ctest` works in a cross build tree.
#   cmake -S tests/cross/aarch64 -B build-aarch64 -DCMAKE_TOOLCHAIN_FILE=cmake/toolchains/aarch64-linux-gnu.cmake
# xsimd picks NEON64 (ARMv8's Advanced SIMD is always present); HANDEMO_ARCH stays `none` (no -march).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
find_program(HANDEMO_QEMU_AARCH64 qemu-aarch64)
if(HANDEMO_QEMU_AARCH64)
  set(CMAKE_CROSSCOMPILING_EMULATOR ${HANDEMO_QEMU_AARCH64} -L /usr/aarch64-linux-gnu)
endif()
