# Precompiled headers. Every unity batch used to parse Eigen, fmt, nlohmann-json, the standard
# containers (and in the tests GoogleTest) again: 2-3 s a batch, in ~180 batches across the
# Release and sanitizer builds of CI. They are now parsed once per kind of target. GCC uses a
# precompiled header only where the flags match those it was made with (otherwise it parses the
# header text, correct but slow), so each kind has its own, made by an object library with that
# kind's flags: the libraries (position-independent), the programs, and the test programs (-O1).
option(HNN_PCH "Precompile the third-party and standard headers the sources share" ON)

set(hnn_pch_headers <algorithm> <array> <cmath> <cstdint> <filesystem> <fstream> <functional>
  <map> <memory> <numeric> <optional> <random> <sstream> <stdexcept> <string> <string_view>
  <utility> <vector> <Eigen/Core> <fmt/format.h> <fmt/ranges.h> <nlohmann/json.hpp>)

# hnn_precompiled_headers(target kind): target reuses the precompiled headers of its kind
# (library, program or test), made on first use.
function(hnn_precompiled_headers target kind)
  if(NOT HNN_PCH)
    return()
  endif()
  set(maker hnn_pch_${kind})
  if(NOT TARGET ${maker})
    set(source ${PROJECT_BINARY_DIR}/pch/${kind}.cpp)
    file(CONFIGURE OUTPUT ${source} CONTENT "// The object that makes the ${kind} kind's precompiled headers.\n")
    add_library(${maker} OBJECT ${source})
    target_link_libraries(${maker} PRIVATE Eigen3::Eigen fmt::fmt hnn_build_flags)
    target_compile_definitions(${maker} PRIVATE EIGEN_MAX_ALIGN_BYTES=64
      EIGEN_MAX_STATIC_ALIGN_BYTES=64)
    set(headers ${hnn_pch_headers})
    if(kind STREQUAL "library")
      set_target_properties(${maker} PROPERTIES POSITION_INDEPENDENT_CODE ON)
    elseif(kind STREQUAL "test")
      target_link_libraries(${maker} PRIVATE GTest::gtest hnn_test_flags)
      list(APPEND headers <gtest/gtest.h>)
    endif()
    target_precompile_headers(${maker} PRIVATE ${headers})
  endif()
  target_precompile_headers(${target} REUSE_FROM ${maker})
endfunction()
