# Precompiled headers: every source of the project parses Eigen, TBB (through
# engine/parallel.h) and the model's tables, about 5 s of each compile on this
# machine kind. Precompiling them once per target roughly halves a fresh
# build (`make demo` must finish in minutes on 2 cores, build included).
option(ATELIER_PCH "Precompile the common heavy headers" ON)

# Extra headers of this target may follow the target name.
function(atelier_precompile target)
  if(NOT ATELIER_PCH)
    return()
  endif()
  target_precompile_headers(${target} PRIVATE
    <algorithm> <array> <cmath> <cstdint> <functional> <map> <memory> <span> <string> <vector>
    <Eigen/Core> <Eigen/Geometry> <nlohmann/json.hpp>
    <atelier/engine/parallel.h>
    <atelier/storage/model.h>
    ${ARGN})
endfunction()
