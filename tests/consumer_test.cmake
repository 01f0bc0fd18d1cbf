# The CMake package end to end: install this build tree into a fresh prefix,
# configure and build examples/consumer against it with find_package(springlab),
# and run the result (which checks its hanging mass against m g / k); build
# examples/plugins against it too and run them with the installed springlab
# (run --plugin, check --plugin); with
# -DPYTHON and -DPYTHON_DIR (the module's folder under the prefix), import
# the installed Python module from there and run a scene.
# Arguments: -DBINARY_DIR -DSOURCE_DIR -DWORK_DIR -DGENERATOR -DCXX [-DPYTHON -DPYTHON_DIR]
file(REMOVE_RECURSE ${WORK_DIR})
function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "failed (${status}): ${ARGN}\n${out}")
  endif()
  message(STATUS "${out}")
endfunction()
run(${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${WORK_DIR}/prefix)
foreach(file lib/cmake/springlab/springlabConfig.cmake include/springlab/models/core/scene.h bin/springlab)
  if(NOT EXISTS ${WORK_DIR}/prefix/${file})
    message(FATAL_ERROR "cmake --install did not put ${file} in place")
  endif()
endforeach()
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/consumer -B ${WORK_DIR}/build -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(${WORK_DIR}/build/hanging_spring)
# A student's plug-in (examples/plugins, docs/your-own-integrator.md) built
# against the installed package and run by the installed springlab: a cloth
# with the implicit Euler (Newton), then check on the symplectic Euler (its
# four declared claims, exit 1 on any FAIL).
run(${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples/plugins -B ${WORK_DIR}/plugins -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix)
run(${CMAKE_COMMAND} --build ${WORK_DIR}/plugins)
set(plugin ${WORK_DIR}/plugins/libmy_methods.so)
execute_process(COMMAND ${WORK_DIR}/prefix/bin/springlab run cloth -p n=6 --plugin ${plugin}
                        --integrator my-implicit-euler --dt 0.02 --t-end 0.2 --json
                RESULT_VARIABLE status OUTPUT_VARIABLE cloth ERROR_VARIABLE err)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "springlab run --plugin failed (${status}): ${err}")
endif()
string(JSON steps GET "${cloth}" steps)
string(JSON iterations GET "${cloth}" newton_iterations)
if(NOT steps EQUAL 10 OR NOT iterations GREATER_EQUAL 10)
  message(FATAL_ERROR "the plug-in's my-implicit-euler ran ${steps} steps (10 expected) with "
                      "${iterations} Newton iterations (at least one a step expected)")
endif()
run(${WORK_DIR}/prefix/bin/springlab check my-symplectic-euler --plugin ${plugin})
if(PYTHON AND NOT IS_ABSOLUTE "${PYTHON_DIR}")
  # A script file: run() takes its arguments as a CMake list, which a
  # one-line `python -c` with semicolons would split.
  file(WRITE ${WORK_DIR}/installed_module.py [=[
import os
import springlab
prefix = os.environ["SPRINGLAB_PREFIX"]
assert springlab.__file__.startswith(prefix + os.sep), springlab.__file__
r = springlab.run(springlab.load_scene("spring"), "implicit-euler", dt=0.01, t_end=1)
assert r["status"] == "completed", r["status"]
print("installed module", springlab.__file__, "ran", r["stats"]["steps"], "steps")
]=])
  run(${CMAKE_COMMAND} -E env PYTHONPATH=${WORK_DIR}/prefix/${PYTHON_DIR}
      SPRINGLAB_PREFIX=${WORK_DIR}/prefix PYTHONDONTWRITEBYTECODE=1
      ${PYTHON} ${WORK_DIR}/installed_module.py)
endif()
