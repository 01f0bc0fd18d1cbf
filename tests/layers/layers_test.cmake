# layers_are_enforced (tests/CMakeLists.txt): the build, not a script, keeps
# the wings' arrows pointing down (cmake/Wings.cmake). Builds four probe
# targets of the real build tree (excluded from the default build): an
# upward include must fail to compile with "No such file", an upward call
# must fail to link naming the symbol, and the same include and call
# downward must build. -DBUILD_DIR=<the build tree>.
function(build target expect_ok pattern)
  execute_process(COMMAND ${CMAKE_COMMAND} --build ${BUILD_DIR} --target ${target}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(expect_ok AND NOT rc EQUAL 0)
    message(FATAL_ERROR "${target} should build, and failed:\n${out}${err}")
  endif()
  if(NOT expect_ok)
    if(rc EQUAL 0)
      message(FATAL_ERROR "${target} built: the wings do not stop it")
    endif()
    string(REGEX MATCH "${pattern}" hit "${out}${err}")
    if(NOT hit)
      message(FATAL_ERROR "${target} failed, but not with '${pattern}':\n${out}${err}")
    endif()
  endif()
endfunction()

build(springlab_probe_downward_include TRUE "")
build(springlab_probe_upward_include FALSE "models/bodies/bodies.h: No such file")
build(springlab_probe_downward_call TRUE "")
build(springlab_probe_upward_call FALSE "undefined reference to `springlab::element_kinds\\(\\)'")
message(STATUS "layers: an upward include and an upward call are refused by the build; "
               "the same downward build")
