# springlab_add_plugin(<target> <source>...): a plug-in of your own
# integrators (docs/your-own-integrator.md), lib<target>.so, to load with
# `springlab run SCENE --plugin ./lib<target>.so --integrator NAME`.
#
# It is a MODULE library built against springlab::plugin (the headers, no
# library): its calls into springlab are resolved by the springlab that
# loads it, so the registry it registers into is that program's own.
function(springlab_add_plugin target)
  add_library(${target} MODULE ${ARGN})
  target_link_libraries(${target} PRIVATE springlab::plugin)
  # The same floating-point contract as springlab's own build (no fused
  # multiply-add), so a method gives the same numbers in and out of the tree.
  target_compile_options(${target} PRIVATE -ffp-contract=off)
endfunction()
