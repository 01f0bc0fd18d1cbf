# Refuses two experiment definitions of one folder with one output name: the
# report runs each into the same folder, where their files (named by the
# definition's "name", default its kind) would overwrite each other, and the
# reuse stamps (run_experiment.cmake) would take one's results for the
# other's (issue 46).
#   cmake -DDIR=experiments -P check_experiment_names.cmake
if(NOT DEFINED DIR)
  message(FATAL_ERROR "check_experiment_names.cmake: -DDIR=... is required")
endif()
file(GLOB definitions "${DIR}/*.json")
list(SORT definitions)
set(names)
set(files)
foreach(definition IN LISTS definitions)
  file(READ "${definition}" text)
  string(JSON name ERROR_VARIABLE no_name GET "${text}" name)
  if(no_name)
    string(JSON name ERROR_VARIABLE no_kind GET "${text}" experiment)
    if(no_kind)
      continue()  # malformed: springlab says what is wrong when it runs it
    endif()
  endif()
  string(REPLACE ";" "_" entry "${name}")  # (a list entry; springlab's names hold no ';' in practice)
  list(FIND names "${entry}" at)
  if(NOT at EQUAL -1)
    list(GET files ${at} first)
    get_filename_component(a "${first}" NAME)
    get_filename_component(b "${definition}" NAME)
    message(FATAL_ERROR "${DIR}: ${a} and ${b} both have the name '${name}': their results "
                        "would overwrite each other; give one a \"name\" of its own")
  endif()
  list(APPEND names "${entry}")
  list(APPEND files "${definition}")
endforeach()
