# Runs the small experiment definitions in tests/data/experiments, saves the
# integrator table, draws the report from their data twice (the two must be
# byte-identical) and checks it in headless Chromium.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

# Runs a command; a non-zero exit stops the test with `what` and the status.
function(run_step what)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE status)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${what} failed (${status})")
  endif()
endfunction()

file(GLOB definitions "${SOURCE_DIR}/tests/data/experiments/*.json")
list(LENGTH definitions count)
if(count EQUAL 0)
  message(FATAL_ERROR "no experiment definitions in tests/data/experiments")
endif()
foreach(definition IN LISTS definitions)
  run_step("springlab experiment ${definition}"
           "${SPRINGLAB}" experiment "${definition}" --out "${WORK_DIR}/data" --no-progress)
endforeach()
run_step("springlab list --json" "${CMAKE_COMMAND}" -DSPRINGLAB=${SPRINGLAB}
         -DFILE=${WORK_DIR}/data/integrators.json -P "${SOURCE_DIR}/cmake/integrator_table.cmake")
foreach(out IN ITEMS report again)
  run_step("make_report.py (${out})" "${PYTHON}" "${SOURCE_DIR}/report/make_report.py"
           --data "${WORK_DIR}/data" --out "${WORK_DIR}/${out}")
endforeach()
file(GLOB_RECURSE outputs RELATIVE "${WORK_DIR}/report" "${WORK_DIR}/report/*")
foreach(output IN LISTS outputs)
  file(SHA256 "${WORK_DIR}/report/${output}" first)
  file(SHA256 "${WORK_DIR}/again/${output}" second)
  if(NOT first STREQUAL second)
    message(FATAL_ERROR "report/${output} differs between two runs on the same data")
  endif()
endforeach()
run_step("the report in Chromium" "${PYTHON}" "${SOURCE_DIR}/tests/report/check_report.py"
         --html "${WORK_DIR}/report/index.html" --chromium "${CHROMIUM}" --expect-players
         --max-bytes 6000000 --screenshot "${WORK_DIR}/screenshot.png")
