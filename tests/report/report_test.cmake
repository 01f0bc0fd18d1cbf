# Runs the small experiment definitions in tests/data/experiments, draws the
# report from their data and checks it in headless Chromium.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
file(GLOB definitions "${SOURCE_DIR}/tests/data/experiments/*.json")
list(LENGTH definitions count)
if(count EQUAL 0)
  message(FATAL_ERROR "no experiment definitions in tests/data/experiments")
endif()
foreach(definition IN LISTS definitions)
  execute_process(COMMAND "${SPRINGLAB}" experiment "${definition}" --out "${WORK_DIR}/data"
                          --no-progress
                  RESULT_VARIABLE status)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "springlab experiment ${definition} failed (${status})")
  endif()
endforeach()
execute_process(COMMAND "${CMAKE_COMMAND}" -DSPRINGLAB=${SPRINGLAB} -DFILE=${WORK_DIR}/data/integrators.json
                        -P "${SOURCE_DIR}/cmake/integrator_table.cmake"
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "springlab list --json failed (${status})")
endif()
execute_process(COMMAND "${PYTHON}" "${SOURCE_DIR}/report/make_report.py"
                        --data "${WORK_DIR}/data" --out "${WORK_DIR}/report"
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "make_report.py failed (${status})")
endif()
execute_process(COMMAND "${PYTHON}" "${SOURCE_DIR}/tests/report/check_report.py"
                        --html "${WORK_DIR}/report/index.html" --chromium "${CHROMIUM}"
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "the report did not render cleanly in Chromium (${status})")
endif()
