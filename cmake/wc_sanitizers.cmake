# The one place that turns on the sanitizers: address and undefined-behaviour
# sanitizers for every target of a Debug host build of this project (the
# libraries, the host programs and the tests), as STYLE.md asks. Included by
# the top-level CMakeLists.txt before any target is defined, and only when the
# project is built on its own for the host (not when a firmware pulls it in
# with add_subdirectory(), not when cross-compiling).
option(WC_SANITIZE "Debug host builds: -fsanitize=address,undefined -fno-sanitize-recover=all" ON)
if(WC_SANITIZE AND CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
  add_compile_options(
    "$<$<CONFIG:Debug>:-fsanitize=address,undefined;-fno-sanitize-recover=all;-fno-omit-frame-pointer>")
  add_link_options("$<$<CONFIG:Debug>:-fsanitize=address,undefined>")
endif()
