# The layer check (cmake/check_layers.cmake) passes on the checkout and
# stops a tree in which models/ includes experiments/ or integrators/
# includes experiments/, naming the file: -DSOURCE_DIR, -DWORK_DIR.
set(check ${SOURCE_DIR}/cmake/check_layers.cmake)
execute_process(COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${SOURCE_DIR} -P ${check}
                RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "the checkout fails its own layer check:\n${err}")
endif()

foreach(case "models/bad.cc|experiments/simulation.h" "integrators/bad.h|experiments/stability.h"
             "models/materials/bad.cc|integrators/integrator.h")
  string(REPLACE "|" ";" parts "${case}")
  list(GET parts 0 file)
  list(GET parts 1 header)
  file(REMOVE_RECURSE ${WORK_DIR})
  get_filename_component(folder ${WORK_DIR}/${file} DIRECTORY)
  file(MAKE_DIRECTORY ${folder} ${WORK_DIR}/models ${WORK_DIR}/integrators ${WORK_DIR}/experiments)
  file(WRITE ${WORK_DIR}/${file} "#include \"models/scene.h\"\n#include \"${header}\"\n")
  # A downward include beside it is fine.
  file(WRITE ${WORK_DIR}/experiments/fine.cc "#include \"integrators/integrator.h\"\n")
  execute_process(COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${WORK_DIR} -P ${check}
                  RESULT_VARIABLE rc ERROR_VARIABLE err)
  if(rc EQUAL 0)
    message(FATAL_ERROR "${file} including ${header} passed the layer check")
  endif()
  string(FIND "${err}" "${file} includes ${header}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "the layer check's message does not name ${file} and ${header}:\n${err}")
  endif()
  string(FIND "${err}" "fine.cc" fine)
  if(NOT fine EQUAL -1)
    message(FATAL_ERROR "a downward include was refused:\n${err}")
  endif()
endforeach()
file(REMOVE_RECURSE ${WORK_DIR})
message(STATUS "layers: the checkout passes; 3 upward includes refused by name")
