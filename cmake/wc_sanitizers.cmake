# wc_enable_sanitizers(<targets>...): in Debug host builds, address and
# undefined-behaviour sanitizers on the given targets and on the libraries
# under test. The host-debug preset puts -fsanitize=... in CMAKE_C_FLAGS
# already; a plain `cmake -DCMAKE_BUILD_TYPE=Debug` does not, and then this
# adds them (compile flags PRIVATE; the link flag as a build-tree usage
# requirement of wetclutch, so every host executable linking it links the runtimes).
option(WC_SANITIZE "Debug host builds: -fsanitize=address,undefined -fno-sanitize-recover=all" ON)
function(wc_enable_sanitizers)
  if(NOT WC_SANITIZE OR NOT CMAKE_C_COMPILER_ID MATCHES "GNU|Clang")
    return()
  endif()
  string(FIND "${CMAKE_C_FLAGS} ${CMAKE_C_FLAGS_DEBUG}" "-fsanitize" _wc_already)
  if(NOT _wc_already EQUAL -1)
    return()  # the preset (or the user) has them already, for everything
  endif()
  set(_wc_flags -fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer)
  foreach(_wc_target IN LISTS ARGN ITEMS wetclutch wetclutch_can)
    target_compile_options(${_wc_target} PRIVATE "$<$<CONFIG:Debug>:${_wc_flags}>")
  endforeach()
  target_link_options(wetclutch INTERFACE $<BUILD_INTERFACE:$<$<CONFIG:Debug>:-fsanitize=address,undefined>>)
endfunction()
