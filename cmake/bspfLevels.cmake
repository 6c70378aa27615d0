# SPDX-License-Identifier: MIT
# Levels compiled by the build: one bspc run per level, a build step like a
# compile. It depends on its mesh and on bspc, so editing one mesh recompiles
# that level only, a parallel generator (Ninja) compiles levels side by side,
# and, bspc's output being a function of its input and options alone, a build
# cache or build farm can share and distribute the steps.
#
#   bspf_add_level(TARGET name SOURCE mesh OUTPUT file.bspf
#                  [OPTIONS bspc-option...] [DEPENDS file...] [ALL])
#   bspf_add_levels(TARGET name SOURCES mesh... OUTPUT_DIRECTORY dir
#                   [OPTIONS bspc-option...] [DEPENDS file...] [ALL])
#
# TARGET is a new custom target that builds the level(s); make a game depend
# on it (add_dependencies(game name)), or pass ALL to build it by default.
# A relative SOURCE is taken from the current source directory, a relative
# OUTPUT or OUTPUT_DIRECTORY in the current binary directory. bspf_add_levels
# writes each mesh's level as OUTPUT_DIRECTORY/<mesh name without its last
# extension>.bspf, one step each. OPTIONS are bspc's (`--up z --scale 0.03125`),
# the same for every level. DEPENDS names other files a step reads, such as an
# OBJ's material library or a glTF's buffers. Shipped in the bspf package and
# defined in bspf's own build; bspc is the target bspf::bspc.
include_guard(GLOBAL)

# One custom command: SOURCE to OUTPUT, both absolute.
function(_bspf_level_command source output options depends)
  get_filename_component(directory "${output}" DIRECTORY)
  file(MAKE_DIRECTORY "${directory}")
  file(RELATIVE_PATH shown "${CMAKE_BINARY_DIR}" "${output}")
  add_custom_command(
    OUTPUT "${output}"
    COMMAND bspf::bspc "${source}" -o "${output}" --quiet ${options}
    DEPENDS "${source}" bspf::bspc ${depends}
    COMMENT "bspc: compiling level ${shown}"
    VERBATIM COMMAND_EXPAND_LISTS)
endfunction()

# The checks both forms share: no unknown arguments, the keywords named after
# `function` given, a new target name, bspc known. Sets all_keyword.
macro(_bspf_level_checks function)
  if(arg_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "${function}: unknown arguments: ${arg_UNPARSED_ARGUMENTS}")
  endif()
  foreach(keyword TARGET ${ARGN})
    if(NOT arg_${keyword})
      message(FATAL_ERROR "${function}(${arg_TARGET}): ${keyword} is required")
    endif()
  endforeach()
  if(TARGET "${arg_TARGET}")
    message(FATAL_ERROR "${function}: target ${arg_TARGET} already exists")
  endif()
  if(NOT TARGET bspf::bspc)
    message(FATAL_ERROR "${function}: no bspf::bspc: build bspf with BSPF_BUILD_COMPILER=ON, "
                        "or install it with the compiler")
  endif()
  set(all_keyword "")
  if(arg_ALL)
    set(all_keyword ALL)
  endif()
endmacro()

function(bspf_add_level)
  cmake_parse_arguments(PARSE_ARGV 0 arg "ALL" "TARGET;SOURCE;OUTPUT" "OPTIONS;DEPENDS")
  _bspf_level_checks(bspf_add_level SOURCE OUTPUT)
  get_filename_component(source "${arg_SOURCE}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
  get_filename_component(output "${arg_OUTPUT}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  _bspf_level_command("${source}" "${output}" "${arg_OPTIONS}" "${arg_DEPENDS}")
  add_custom_target(${arg_TARGET} ${all_keyword} DEPENDS "${output}")
endfunction()

function(bspf_add_levels)
  cmake_parse_arguments(PARSE_ARGV 0 arg "ALL" "TARGET;OUTPUT_DIRECTORY" "SOURCES;OPTIONS;DEPENDS")
  _bspf_level_checks(bspf_add_levels SOURCES OUTPUT_DIRECTORY)
  get_filename_component(directory "${arg_OUTPUT_DIRECTORY}" ABSOLUTE
                         BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  set(outputs "")
  foreach(mesh IN LISTS arg_SOURCES)
    get_filename_component(source "${mesh}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    get_filename_component(name "${source}" NAME_WLE)
    set(output "${directory}/${name}.bspf")
    if(output IN_LIST outputs)
      message(FATAL_ERROR "bspf_add_levels(${arg_TARGET}): two sources would both write ${output}")
    endif()
    list(APPEND outputs "${output}")
    _bspf_level_command("${source}" "${output}" "${arg_OPTIONS}" "${arg_DEPENDS}")
  endforeach()
  add_custom_target(${arg_TARGET} ${all_keyword} DEPENDS ${outputs})
endfunction()
