# SPDX-License-Identifier: MIT
# bspf_enable_warnings(DIR): the warnings bspf is built with, added as a
# private compile option to every target compiled in DIR and the directories
# below it. Target-level, unlike add_compile_options, so nothing reaches the
# targets of a project that includes bspf.
if(CMAKE_CXX_COMPILER_ID STREQUAL "MSVC")
  set(BSPF_WARNING_FLAGS /W4)
else()
  set(BSPF_WARNING_FLAGS -Wall -Wextra -Wpedantic)
endif()

function(bspf_enable_warnings dir)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  foreach(target IN LISTS targets)
    get_target_property(type ${target} TYPE)
    if(type MATCHES "^(EXECUTABLE|STATIC_LIBRARY|SHARED_LIBRARY|MODULE_LIBRARY|OBJECT_LIBRARY)$")
      target_compile_options(${target} PRIVATE ${BSPF_WARNING_FLAGS})
    endif()
  endforeach()
  get_property(subdirectories DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(subdirectory IN LISTS subdirectories)
    bspf_enable_warnings(${subdirectory})
  endforeach()
endfunction()
