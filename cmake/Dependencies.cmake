# Every dependency is a Debian package; a missing one stops the configure step
# with the exact package to install.
set(SPRINGLAB_APT_HINT "sudo apt-get install -y --no-install-recommends")

macro(springlab_require package debian_package)
  find_package(${package} ${ARGN} QUIET)
  if(NOT ${package}_FOUND)
    message(FATAL_ERROR
      "springlab: dependency ${package} not found.\n"
      "Install it with:  ${SPRINGLAB_APT_HINT} ${debian_package}")
  endif()
endmacro()

springlab_require(Eigen3 libeigen3-dev 3.4 NO_MODULE)
springlab_require(nlohmann_json nlohmann-json3-dev)
springlab_require(CLI11 libcli11-dev)
springlab_require(SUNDIALS libsundials-dev 6.4)
# CHOLMOD (SuiteSparse) factors the implicit methods' positive definite
# Newton matrices (supernodal LL^T); its dense blocks run in OpenBLAS, linked
# directly so springlab can set its thread count (integrators/
# sparse_direct_solver.h). No CMake config ships with either: look for the
# header and the libraries.
find_path(SPRINGLAB_CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(SPRINGLAB_CHOLMOD_LIBRARY cholmod)
if(NOT SPRINGLAB_CHOLMOD_INCLUDE_DIR OR NOT SPRINGLAB_CHOLMOD_LIBRARY)
  message(FATAL_ERROR
    "springlab: dependency CHOLMOD (SuiteSparse) not found.\n"
    "Install it with:  ${SPRINGLAB_APT_HINT} libsuitesparse-dev")
endif()
find_library(SPRINGLAB_OPENBLAS_LIBRARY openblas)
if(NOT SPRINGLAB_OPENBLAS_LIBRARY)
  message(FATAL_ERROR
    "springlab: dependency OpenBLAS not found (CHOLMOD's dense kernels).\n"
    "Install it with:  ${SPRINGLAB_APT_HINT} libopenblas-dev")
endif()
add_library(springlab_cholmod INTERFACE)
target_include_directories(springlab_cholmod INTERFACE ${SPRINGLAB_CHOLMOD_INCLUDE_DIR})
target_link_libraries(springlab_cholmod INTERFACE ${SPRINGLAB_OPENBLAS_LIBRARY}
                      ${SPRINGLAB_CHOLMOD_LIBRARY})
message(STATUS "springlab: CHOLMOD: ${SPRINGLAB_CHOLMOD_LIBRARY}, BLAS: ${SPRINGLAB_OPENBLAS_LIBRARY}")

if(SPRINGLAB_BUILD_TESTS)
  springlab_require(GTest libgtest-dev)
endif()
if(SPRINGLAB_BUILD_BENCHMARKS)
  springlab_require(benchmark libbenchmark-dev)
  springlab_require(Boost libboost-dev 1.71 CONFIG)  # header-only: Boost.Odeint
endif()

# Python 3 draws the report (matplotlib, numpy) and, with the tests on, reads
# the --vtk output back with VTK and executes the example notebook. The
# python3 first on PATH may lack these (a pyenv build, say), so try each
# candidate and keep the first that can import them all.
function(springlab_find_python out imports packages)
  set(candidates)
  if(SPRINGLAB_PYTHON)
    list(APPEND candidates "${SPRINGLAB_PYTHON}")
  endif()
  list(APPEND candidates /usr/bin/python3)
  find_program(_path_python3 NAMES python3 NO_CACHE)
  if(_path_python3)
    list(APPEND candidates "${_path_python3}")
  endif()
  foreach(candidate IN LISTS candidates)
    execute_process(COMMAND "${candidate}" -c "import ${imports}"
                    RESULT_VARIABLE status OUTPUT_QUIET ERROR_QUIET)
    if(status EQUAL 0)
      set(${out} "${candidate}" PARENT_SCOPE)
      return()
    endif()
  endforeach()
  message(FATAL_ERROR
    "springlab: no Python 3 that can import ${imports} (tried: ${candidates}).\n"
    "Install them with:  ${SPRINGLAB_APT_HINT} ${packages}\n"
    "or point -DSPRINGLAB_PYTHON=/path/to/python3 at one that has them.")
endfunction()
springlab_find_python(SPRINGLAB_REPORT_PYTHON "matplotlib, numpy" "python3-matplotlib python3-numpy")
message(STATUS "springlab: report Python: ${SPRINGLAB_REPORT_PYTHON}")
if(SPRINGLAB_BUILD_TESTS)
  springlab_find_python(SPRINGLAB_TEST_PYTHON "matplotlib, numpy, vtkmodules.vtkIOXML"
                        "python3-matplotlib python3-numpy python3-vtk9")
  message(STATUS "springlab: test Python: ${SPRINGLAB_TEST_PYTHON}")
endif()

if(SPRINGLAB_BUILD_TESTS)
  find_program(SPRINGLAB_CHROMIUM NAMES chromium chromium-browser)
  if(NOT SPRINGLAB_CHROMIUM)
    message(FATAL_ERROR
      "springlab: the report test needs headless Chromium.\n"
      "Install it with:  ${SPRINGLAB_APT_HINT} chromium")
  endif()
endif()
