# cmake/run_experiment.cmake reruns an experiment exactly when its results
# are not current: the first run runs, an unchanged second one is reused
# (its tables untouched), and a change to the scene file the definition
# names (whatever its extension: drop.scene, issue 46), to the definition,
# to the springlab executable (a copy with one byte more) or a missing table
# each make it run again.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(out "${WORK_DIR}/data")
set(definition "${WORK_DIR}/reuse.json")

function(write_inputs mass integrators)
  file(WRITE "${WORK_DIR}/drop.scene" "{\"name\": \"drop\", \"dimension\": 2, \"gravity\": [0, -9.81],
  \"contact\": {\"model\": \"penalty\", \"stiffness\": 1e4},
  \"planes\": [{\"point\": [0, 0], \"normal\": [0, 1]}],
  \"particles\": [{\"x\": [0, 0.1], \"mass\": ${mass}}, {\"x\": [0, 0], \"fixed\": true}],
  \"springs\": []}\n")
  file(WRITE "${definition}" "{\"experiment\": \"energy\", \"name\": \"reuse\",
  \"integrators\": [${integrators}],
  \"cases\": [{\"scene\": \"drop.scene\", \"dt\": 0.01, \"t_end\": 0.1}]}\n")
endfunction()

# Runs the script; `expect` is "ran" or "reused".
function(step what springlab expect)
  execute_process(COMMAND "${CMAKE_COMMAND}" -DSPRINGLAB=${springlab} -DDEFINITION=${definition}
                          -DOUT=${out} -P "${SOURCE_DIR}/cmake/run_experiment.cmake"
                  RESULT_VARIABLE status OUTPUT_VARIABLE output ERROR_VARIABLE output)
  if(NOT status EQUAL 0)
    message(FATAL_ERROR "${what}: run_experiment.cmake failed (${status}):\n${output}")
  endif()
  string(FIND "${output}" "[reuse] reused:" at)
  if(expect STREQUAL "reused" AND at EQUAL -1)
    message(FATAL_ERROR "${what}: expected the results to be reused, but the experiment ran:\n"
                        "${output}")
  elseif(expect STREQUAL "ran" AND NOT at EQUAL -1)
    message(FATAL_ERROR "${what}: expected the experiment to run, but it was reused:\n${output}")
  endif()
  if(NOT EXISTS "${out}/reuse.stamp")
    message(FATAL_ERROR "${what}: no stamp reuse.stamp after the step")
  endif()
endfunction()

write_inputs(1.0 "\"symplectic-euler\"")
step("first run" "${SPRINGLAB}" ran)
file(SHA256 "${out}/reuse-runs.csv" runs_before)
step("nothing changed" "${SPRINGLAB}" reused)
file(SHA256 "${out}/reuse-runs.csv" runs_after)
if(NOT runs_before STREQUAL runs_after)
  message(FATAL_ERROR "nothing changed: the reused reuse-runs.csv was rewritten")
endif()

write_inputs(2.0 "\"symplectic-euler\"")
step("the scene file changed" "${SPRINGLAB}" ran)
step("nothing changed after it" "${SPRINGLAB}" reused)

write_inputs(2.0 "\"symplectic-euler\", \"implicit-euler\"")
step("the definition changed" "${SPRINGLAB}" ran)

# The same program with one byte more at its end: another executable.
file(COPY "${SPRINGLAB}" DESTINATION "${WORK_DIR}/bin")
get_filename_component(exe "${SPRINGLAB}" NAME)
file(APPEND "${WORK_DIR}/bin/${exe}" "\n")
step("springlab changed" "${WORK_DIR}/bin/${exe}" ran)
step("the same changed springlab" "${WORK_DIR}/bin/${exe}" reused)

file(REMOVE "${out}/reuse-runs.csv")
step("a table is missing" "${WORK_DIR}/bin/${exe}" ran)
if(NOT EXISTS "${out}/reuse-runs.csv")
  message(FATAL_ERROR "a table is missing: the rerun did not write reuse-runs.csv")
endif()
