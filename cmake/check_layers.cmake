# The layers of springlab and what each may include (issue #32, docs/layout.md):
#
#   models/       the physics: models/ only (it knows nothing of time stepping)
#   integrators/  time stepping: integrators/ and models/ (nothing of experiments)
#   experiments/  the driver, outputs and experiment kinds: the three above
#
# benchmarks/, python/, fuzz/ and tests/ sit on top and may include any of
# them; report/ is Python and reads data only. Run at every build (the
# check_layers target, which the library depends on), so an include that
# runs upward fails the build with the file, the line and the rule:
#
#   cmake -DSOURCE_DIR=<checkout> -P cmake/check_layers.cmake
if(NOT SOURCE_DIR)
  message(FATAL_ERROR "check_layers: give -DSOURCE_DIR=<the checkout>")
endif()

# layer folder -> the folders of the project it may not include from
set(forbidden_models "integrators|experiments|benchmarks|python|fuzz|tests")
set(forbidden_integrators "experiments|benchmarks|python|fuzz|tests")
set(forbidden_experiments "benchmarks|python|fuzz|tests")
set(why_models "models/ is the physics: it knows nothing of time stepping or experiments")
set(why_integrators "integrators/ is time stepping: it sees models only through MechanicalSystem")
set(why_experiments "experiments/ drives models and integrators; the tools on top include it, not the reverse")

set(problems "")
foreach(layer models integrators experiments)
  file(GLOB_RECURSE files "${SOURCE_DIR}/${layer}/*.h" "${SOURCE_DIR}/${layer}/*.cc")
  list(SORT files)
  foreach(path IN LISTS files)
    file(STRINGS "${path}" lines REGEX "^[ \t]*#[ \t]*include[ \t]*\"")
    foreach(line IN LISTS lines)
      if(line MATCHES "#[ \t]*include[ \t]*\"((${forbidden_${layer}})/[^\"]*)\"")
        file(RELATIVE_PATH relative "${SOURCE_DIR}" "${path}")
        string(APPEND problems
               "  ${relative} includes ${CMAKE_MATCH_1}: ${why_${layer}}\n")
      endif()
    endforeach()
  endforeach()
endforeach()

if(problems)
  message(FATAL_ERROR "check_layers: an include runs upward through the layers "
                      "(models <- integrators <- experiments <- tools):\n${problems}")
endif()
