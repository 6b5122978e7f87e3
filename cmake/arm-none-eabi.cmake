# Cross-compiling for a Cortex-M4F with Debian's gcc-arm-none-eabi (newlib):
#   cmake -DCMAKE_TOOLCHAIN_FILE=cmake/arm-none-eabi.cmake -S examples/embedded -B build-embedded
# Hard-float ABI with the FPv4 single-precision unit (float in hardware, double in software).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
set(CMAKE_SIZE arm-none-eabi-size)
# No executable can be run while CMake checks the compiler: test it with a static library.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(MJUKF_CORTEX_M4F_FLAGS "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16")
set(CMAKE_C_FLAGS_INIT "${MJUKF_CORTEX_M4F_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT "${MJUKF_CORTEX_M4F_FLAGS}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${MJUKF_CORTEX_M4F_FLAGS}")

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
