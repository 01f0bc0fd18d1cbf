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
if(SPRINGLAB_BUILD_TESTS)
  springlab_require(GTest libgtest-dev)
endif()
