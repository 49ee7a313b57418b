# Toolchain: Cortex-M4F (single-precision FPU, hard-float ABI), arm-none-eabi-gcc.
#   cmake --preset cortex-m4f          (or -DCMAKE_TOOLCHAIN_FILE=cmake/arm-none-eabi.cmake)
# Bare metal: no OS, so CMake's compiler checks build a static library instead
# of linking an executable (which would need a startup file and linker script).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

set(WC_ARM_TOOLCHAIN_PREFIX arm-none-eabi- CACHE STRING "Prefix of the cross tools")
set(CMAKE_C_COMPILER ${WC_ARM_TOOLCHAIN_PREFIX}gcc)
set(CMAKE_ASM_COMPILER ${WC_ARM_TOOLCHAIN_PREFIX}gcc)

# The core and its ABI belong to every compile and link. These _INIT values only
# seed the cache: a CMAKE_C_FLAGS given on the command line or by a preset
# replaces them, so it must repeat the -mcpu/-mfloat-abi/-mfpu flags.
set(WC_ARM_CPU_FLAGS "-mcpu=cortex-m4 -mthumb -mfloat-abi=hard -mfpu=fpv4-sp-d16")
set(CMAKE_C_FLAGS_INIT "${WC_ARM_CPU_FLAGS}")
set(CMAKE_ASM_FLAGS_INIT "${WC_ARM_CPU_FLAGS}")
set(CMAKE_EXE_LINKER_FLAGS_INIT "${WC_ARM_CPU_FLAGS} -Wl,--gc-sections --specs=nano.specs --specs=nosys.specs")

# Look for libraries and headers in the target's sysroot only, programs on the host.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
