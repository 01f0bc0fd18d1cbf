# Saves `springlab list --json` (every integrator's facts, family, colour and
# marker) as FILE, the table the report draws every integrator from; written
# whole or not at all.
#   cmake -DSPRINGLAB=path/to/springlab -DFILE=report-data/integrators.json -P integrator_table.cmake
get_filename_component(dir "${FILE}" DIRECTORY)
file(MAKE_DIRECTORY "${dir}")
execute_process(COMMAND "${SPRINGLAB}" list --json OUTPUT_FILE "${FILE}.tmp"
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  file(REMOVE "${FILE}.tmp")
  message(FATAL_ERROR "springlab list --json failed (${status})")
endif()
file(RENAME "${FILE}.tmp" "${FILE}")
