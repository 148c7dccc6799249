# Third-party dependencies, all from Debian packages (see scripts/setup).
# Each is found here once; layers link only what they need.

find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(PkgConfig REQUIRED)
pkg_check_modules(FFTW3 REQUIRED IMPORTED_TARGET fftw3)
# Required: the lowest modes of large 3D BEM basins (fluid/lowest_modes.hpp).
pkg_check_modules(ARPACK REQUIRED IMPORTED_TARGET arpack)
pkg_check_modules(CAIRO REQUIRED IMPORTED_TARGET cairo)  # pictures (apps/viz)
find_package(HDF5 REQUIRED COMPONENTS C)
find_package(tomlplusplus REQUIRED)
find_package(CLI11 REQUIRED)

# SuiteSparse 5.x in Debian ships no CMake config for CHOLMOD: find it by hand.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse REQUIRED)
find_library(CHOLMOD_LIBRARY cholmod REQUIRED)
find_library(SUITESPARSECONFIG_LIBRARY suitesparseconfig REQUIRED)
find_library(UMFPACK_LIBRARY umfpack REQUIRED)
find_library(KLU_LIBRARY klu REQUIRED)  # Lemke's reduced basis (contact/lcp/lemke.hpp)
add_library(floesim_suitesparse INTERFACE)
target_include_directories(floesim_suitesparse SYSTEM INTERFACE ${CHOLMOD_INCLUDE_DIR})
target_link_libraries(floesim_suitesparse INTERFACE ${UMFPACK_LIBRARY} ${KLU_LIBRARY} ${CHOLMOD_LIBRARY}
                      ${SUITESPARSECONFIG_LIBRARY})

# CGAL is header-only; only the layers that mesh or partition polygons use it.
find_package(CGAL QUIET)

add_library(floesim_hdf5 INTERFACE)
target_include_directories(floesim_hdf5 SYSTEM INTERFACE ${HDF5_INCLUDE_DIRS})
target_link_libraries(floesim_hdf5 INTERFACE ${HDF5_C_LIBRARIES})
target_compile_definitions(floesim_hdf5 INTERFACE ${HDF5_DEFINITIONS})

if(FLOESIM_BUILD_TESTS)
  find_package(doctest REQUIRED)
  include(doctest)
endif()
