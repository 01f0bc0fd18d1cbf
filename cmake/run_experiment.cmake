# Runs one experiment definition for the report, unless its results in OUT
# are current: the report after `cmake --workflow --preset bench` (or after
# drawing changes in report/) then takes seconds, not minutes.
#   cmake -DSPRINGLAB=path/to/springlab -DDEFINITION=experiments/x.json -DOUT=report-data
#         [-DPLUGIN_PATH=build/release/plugins] [-DPYTHON=python3 -DPYTHON_MODULE_DIR=build/release/python]
#         -P run_experiment.cmake
# A definition that names its own methods ("plugins", "python":
# docs/your-own-integrator.md) finds plug-ins named by a plain file name in
# PLUGIN_PATH, and one with "python" runs through the Python module
# (springlab.experiment) instead of the command line.
# Results are current when OUT/<name>.stamp, written after the run succeeded,
# holds the SHA-256 of the definition, of every file it names (each string of
# the definition that is the path of a file next to it, whatever its
# extension: a scene file, a data file) and of the springlab executable,
# exactly as they are now, and the settings file
# OUT/<name>.json and every table it lists are there. Anything else reruns
# the experiment (delete the stamp to force it). The stamp holds hashes only,
# no time: the same inputs give the same stamp.
foreach(var IN ITEMS SPRINGLAB DEFINITION OUT)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_experiment.cmake: -D${var}=... is required")
  endif()
endforeach()

file(READ "${DEFINITION}" text)
# The output files are named by the definition's "name" (default: its kind).
string(JSON name ERROR_VARIABLE no_name GET "${text}" name)
if(no_name)
  string(JSON name ERROR_VARIABLE no_kind GET "${text}" experiment)
  if(no_kind)
    # Malformed: springlab says what is wrong, with the file and line.
    set(name "")
  endif()
endif()

# What the results depend on.
file(SHA256 "${DEFINITION}" hash)
set(stamp_text "definition ${hash}\n")
get_filename_component(definition_dir "${DEFINITION}" DIRECTORY)
# Every string: a scene named "drop.scene" is a file as much as "drop.json"
# (issue 46: its changes were reported as unchanged results).
string(REGEX MATCHALL "\"[^\"]+\"" named "${text}")
list(REMOVE_DUPLICATES named)
foreach(quoted IN LISTS named)
  string(REGEX REPLACE "^\"(.*)\"$" "\\1" scene "${quoted}")
  set(path "${definition_dir}/${scene}")  # springlab reads it relative to the definition
  if(IS_ABSOLUTE "${scene}")
    set(path "${scene}")
  endif()
  if(EXISTS "${path}" AND NOT IS_DIRECTORY "${path}")
    file(SHA256 "${path}" hash)
    string(APPEND stamp_text "scene ${scene} ${hash}\n")
  endif()
endforeach()
file(SHA256 "${SPRINGLAB}" hash)
string(APPEND stamp_text "springlab ${hash}\n")
# Plug-ins (plain names, found in PLUGIN_PATH) and, for Python methods, the module.
string(REGEX MATCHALL "\"[^\"/]+\\.so\"" plugins "${text}")
foreach(quoted IN LISTS plugins)
  string(REGEX REPLACE "^\"(.*)\"$" "\\1" plugin "${quoted}")
  if(DEFINED PLUGIN_PATH AND EXISTS "${PLUGIN_PATH}/${plugin}")
    file(SHA256 "${PLUGIN_PATH}/${plugin}" hash)
    string(APPEND stamp_text "plugin ${plugin} ${hash}\n")
  endif()
endforeach()
string(JSON python_files ERROR_VARIABLE no_python GET "${text}" python)
set(uses_python FALSE)
if(NOT no_python)
  set(uses_python TRUE)
  file(GLOB module "${PYTHON_MODULE_DIR}/springlab*.so")
  foreach(m IN LISTS module)
    file(SHA256 "${m}" hash)
    string(APPEND stamp_text "module ${hash}\n")
  endforeach()
endif()

set(stamp "${OUT}/${name}.stamp")
set(current FALSE)
if(NOT name STREQUAL "" AND EXISTS "${stamp}" AND EXISTS "${OUT}/${name}.json")
  file(READ "${stamp}" old)
  if(old STREQUAL stamp_text)
    set(current TRUE)
    file(READ "${OUT}/${name}.json" settings)
    string(JSON complete ERROR_VARIABLE err GET "${settings}" complete)
    if(err OR NOT complete)
      set(current FALSE)
    endif()
    string(JSON tables ERROR_VARIABLE err LENGTH "${settings}" tables)
    if(err)
      set(current FALSE)
      set(tables 0)
    endif()
    if(tables GREATER 0)
      math(EXPR last "${tables} - 1")
      foreach(k RANGE ${last})
        string(JSON table ERROR_VARIABLE err GET "${settings}" tables ${k} file)
        if(err OR NOT EXISTS "${OUT}/${table}")
          set(current FALSE)
        endif()
      endforeach()
    endif()
  endif()
endif()

if(current)
  message("[${name}] reused: the definition, its scene files and springlab are unchanged "
          "(delete ${stamp} to run it again)")
  return()
endif()

if(NOT name STREQUAL "")
  file(REMOVE "${stamp}")
endif()
set(plugin_env)
if(DEFINED PLUGIN_PATH)
  set(plugin_env "SPRINGLAB_PLUGIN_PATH=${PLUGIN_PATH}")
endif()
if(uses_python)
  file(GLOB module "${PYTHON_MODULE_DIR}/springlab*.so")
  if(NOT PYTHON OR NOT module)
    message("[${name}] skipped: its Python methods need the Python module (pybind11-dev python3-dev)")
    return()
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E env ${plugin_env} "PYTHONPATH=${PYTHON_MODULE_DIR}"
                          PYTHONDONTWRITEBYTECODE=1 "${PYTHON}" -c
                          "import sys, springlab; springlab.experiment(sys.argv[1], out=sys.argv[2])"
                          "${DEFINITION}" "${OUT}"
                  RESULT_VARIABLE status)
else()
  execute_process(COMMAND ${CMAKE_COMMAND} -E env ${plugin_env}
                          "${SPRINGLAB}" experiment "${DEFINITION}" --out "${OUT}"
                  RESULT_VARIABLE status)
endif()
if(NOT status EQUAL 0)
  message(FATAL_ERROR "springlab experiment ${DEFINITION} failed (exit status ${status})")
endif()
if(NOT name STREQUAL "")
  file(WRITE "${stamp}.tmp" "${stamp_text}")
  file(RENAME "${stamp}.tmp" "${stamp}")
endif()
