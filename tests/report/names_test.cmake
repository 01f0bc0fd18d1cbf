# cmake/check_experiment_names.cmake: a folder of definitions with distinct
# names passes (the course's own experiments/ too); two with one name, one
# given and one the kind's default, are refused, naming both files.
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(script "${SOURCE_DIR}/cmake/check_experiment_names.cmake")

function(check dir expect_ok expected)
  execute_process(COMMAND "${CMAKE_COMMAND}" -DDIR=${dir} -P "${script}"
                  RESULT_VARIABLE status OUTPUT_VARIABLE output ERROR_VARIABLE output)
  if(expect_ok AND NOT status EQUAL 0)
    message(FATAL_ERROR "${dir}: refused, expected to pass:\n${output}")
  endif()
  if(NOT expect_ok)
    string(REGEX REPLACE "[ \n]+" " " flat "${output}")
    string(FIND "${flat}" "${expected}" at)
    if(status EQUAL 0 OR at EQUAL -1)
      message(FATAL_ERROR "${dir}: expected a refusal saying '${expected}', got (${status}):\n"
                          "${output}")
    endif()
  endif()
endfunction()

check("${SOURCE_DIR}/experiments" TRUE "")
file(WRITE "${WORK_DIR}/a.json" "{\"experiment\": \"energy\", \"name\": \"drop\"}\n")
file(WRITE "${WORK_DIR}/b.json" "{\"experiment\": \"energy\"}\n")
check("${WORK_DIR}" TRUE "")
file(WRITE "${WORK_DIR}/c.json" "{\"experiment\": \"rigid\", \"name\": \"energy\"}\n")
check("${WORK_DIR}" FALSE "b.json and c.json both have the name 'energy': their results would overwrite each other")
