# The wings (docs/layout.md): every sub-folder of models/, integrators/ and
# experiments/ is a library of its own, linked only to the wings below it.
# The build, not a script, says what may call what:
#
#   - a wing compiles with the headers of its own folder and of the wings it
#     names in DEPENDS (and theirs), each seen through a folder of links in
#     the build tree (build/<preset>/wings/<wing>/), never the source tree
#     itself: `#include "models/bodies/bodies.h"` in a wing that does not
#     depend on models/bodies fails to compile ("No such file");
#   - every wing is also linked once as a shared object with
#     -Wl,--no-undefined against its DEPENDS only (the target
#     springlab_<wing>_closed, part of the default build): a call into a wing
#     it does not depend on, even through a declaration written by hand,
#     fails to link, naming the symbol.
#
# springlab_wing(<wing> FOLDERS <folder>... [DEPENDS <wing>...]
#                [LINK <target>...] [EXCLUDE <regex>])
# <wing> is the target's suffix (models_core -> springlab_models_core).

set(SPRINGLAB_WINGS "" CACHE INTERNAL "the wing targets, bottom up")
set(closed_default ON)
if(CMAKE_CXX_FLAGS MATCHES "-fsanitize" OR SPRINGLAB_BUILD_FUZZERS)
  set(closed_default OFF)
endif()
option(SPRINGLAB_CLOSED_WINGS "Link each wing alone with -Wl,--no-undefined (off under sanitizers and fuzzers)"
       ${closed_default})
set(SPRINGLAB_WING_HEADERS_ROOT ${PROJECT_BINARY_DIR}/wings)
# A unity build: each wing's files compiled SPRINGLAB_UNITY_BATCH at a time,
# as one translation unit (CMake's UNITY_BUILD), so that the headers every
# file includes (Eigen, the standard library, nlohmann/json) are parsed and
# their templates instantiated once per batch instead of once per file
# (docs/performance.md "Build time"). Names private to a file (anonymous
# namespaces) must then differ within a wing. -DSPRINGLAB_UNITY=OFF compiles
# file by file (an edit then recompiles one file, not its batch).
option(SPRINGLAB_UNITY "Compile each wing's files in batches (a unity build)" ON)
set(SPRINGLAB_UNITY_BATCH 8 CACHE STRING "files per unity batch")

function(springlab_wing wing)
  cmake_parse_arguments(arg "" "" "FOLDERS;DEPENDS;LINK;EXCLUDE" ${ARGN})
  set(target springlab_${wing})
  set(headers_dir ${SPRINGLAB_WING_HEADERS_ROOT}/${wing})
  set(sources)
  foreach(folder IN LISTS arg_FOLDERS)
    file(GLOB folder_sources CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/${folder}/*.cc)
    file(GLOB folder_headers CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/${folder}/*.h)
    if(arg_EXCLUDE)
      list(FILTER folder_sources EXCLUDE REGEX "${arg_EXCLUDE}")
    endif()
    list(APPEND sources ${folder_sources})
    # The wing's headers, as links under the path they are included by.
    file(MAKE_DIRECTORY ${headers_dir}/${folder})
    file(GLOB stale ${headers_dir}/${folder}/*.h)
    foreach(link IN LISTS stale)
      get_filename_component(name ${link} NAME)
      if(NOT EXISTS ${PROJECT_SOURCE_DIR}/${folder}/${name})
        file(REMOVE ${link})
      endif()
    endforeach()
    foreach(header IN LISTS folder_headers)
      get_filename_component(name ${header} NAME)
      if(NOT IS_SYMLINK ${headers_dir}/${folder}/${name})
        file(CREATE_LINK ${header} ${headers_dir}/${folder}/${name} SYMBOLIC)
      endif()
    endforeach()
  endforeach()
  if(NOT sources)
    message(FATAL_ERROR "springlab: the wing ${wing} (${arg_FOLDERS}) has no source file")
  endif()

  add_library(${target} STATIC ${sources})
  set_target_properties(${target} PROPERTIES POSITION_INDEPENDENT_CODE ON
                        OUTPUT_NAME springlab_${wing} EXPORT_NAME ${wing})
  if(SPRINGLAB_UNITY)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON
                          UNITY_BUILD_BATCH_SIZE ${SPRINGLAB_UNITY_BATCH})
  endif()
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${headers_dir}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/springlab>)
  set(deps)
  foreach(dep IN LISTS arg_DEPENDS)
    list(APPEND deps springlab_${dep})
  endforeach()
  target_link_libraries(${target} PUBLIC ${deps} ${arg_LINK})

  # The closed link: the whole wing, resolved against its DEPENDS alone
  # (not under the sanitizers, whose runtime only an executable links).
  if(NOT SPRINGLAB_CLOSED_WINGS)
    set(SPRINGLAB_WINGS ${SPRINGLAB_WINGS} ${target} CACHE INTERNAL "the wing targets, bottom up")
    return()
  endif()
  set(stub ${PROJECT_BINARY_DIR}/wings/closed_stub.cc)
  if(NOT EXISTS ${stub})
    file(WRITE ${stub} "// A shared object of one wing and its dependencies (cmake/Wings.cmake).\n")
  endif()
  add_library(${target}_closed SHARED ${stub})
  target_link_libraries(${target}_closed PRIVATE
    "$<LINK_LIBRARY:WHOLE_ARCHIVE,${target}>" ${deps} ${arg_LINK})
  target_link_options(${target}_closed PRIVATE -Wl,--no-undefined)
  set_target_properties(${target}_closed PROPERTIES LIBRARY_OUTPUT_DIRECTORY
                        ${PROJECT_BINARY_DIR}/wings/closed)

  set(SPRINGLAB_WINGS ${SPRINGLAB_WINGS} ${target} CACHE INTERNAL "the wing targets, bottom up")
endfunction()
