# What `cmake --install build --prefix P` puts under P (README.md, "Install"):
#   bin/floesim                                   the command line
#   lib*/libfloesim.so.X.Y.Z (+ SONAME link)      the library: core, fluid, contact, parallel, coupling
#   include/floesim/{core,fluid,contact,parallel,coupling} its public headers
#   lib*/cmake/floesim/                           find_package(floesim) -> floesim::floesim
#   lib*/pkgconfig/floesim.pc                     pkg-config --cflags --libs floesim
#   FLOESIM_INSTALL_PYTHONDIR/floesim/            the Python package (python/CMakeLists.txt)
#   share/man/man1/floesim.1                      every subcommand's --help, as a man page
#   share/floesim/{examples,data}                 the examples and the data they read
#   share/doc/floesim/                            README.md and docs/
# lib* is GNUInstallDirs' CMAKE_INSTALL_LIBDIR (lib, or lib/<multiarch> when P is /usr).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# The library a user links: one shared object made of the five layer
# libraries, whole (a user may call any public function, so every object of
# each archive goes in, not only those some code of ours needs). The layers
# stay static libraries for the tool, the tests and the Python module, so the
# in-tree build is unchanged; their objects are position-independent
# (CMAKE_POSITION_INDEPENDENT_CODE, set in the top CMakeLists.txt).
set(_layers floesim_core floesim_fluid floesim_contact floesim_parallel floesim_coupling)
set(_stub ${PROJECT_BINARY_DIR}/floesim_library_stub.cpp)
file(CONFIGURE OUTPUT ${_stub} CONTENT "// libfloesim.so is made of the layer archives linked whole.\n")
add_library(floesim_library SHARED ${_stub})
add_library(floesim::floesim ALIAS floesim_library)
set(_whole)
foreach(layer IN LISTS _layers)
  list(APPEND _whole "$<TARGET_FILE:${layer}>")
endforeach()
target_link_options(floesim_library PRIVATE "LINKER:--whole-archive" ${_whole} "LINKER:--no-whole-archive")
# Linking the top layer also orders the build and brings the third-party
# libraries the layers need (HDF5, FFTW, CHOLMOD, GMP, MPFR, OpenMP, MPI).
target_link_libraries(floesim_library PRIVATE floesim_coupling)
set_target_properties(floesim_library PROPERTIES
  OUTPUT_NAME floesim
  EXPORT_NAME floesim
  VERSION ${PROJECT_VERSION}
  # Before 1.0 every minor version may change the ABI.
  SOVERSION ${PROJECT_VERSION_MAJOR}.${PROJECT_VERSION_MINOR}
  LIBRARY_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/lib)
# What a user's code needs: the headers (written "floesim/core/floe.hpp" or,
# as the library's own headers include each other, "core/floe.hpp"), Eigen
# (public headers use Eigen types) and C++20.
target_include_directories(floesim_library INTERFACE
  $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
  $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>
  $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/floesim>)
target_link_libraries(floesim_library INTERFACE Eigen3::Eigen)
target_compile_features(floesim_library INTERFACE cxx_std_20)

# The tool and the library.
install(TARGETS floesim RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS floesim_library EXPORT floesimTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

# Public headers, in the layout the sources use. core/detail holds the HDF5
# wrapper, which only core's .cpp files include.
install(DIRECTORY core fluid contact parallel coupling
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/floesim
  FILES_MATCHING PATTERN "*.hpp"
  PATTERN "detail" EXCLUDE)

# The CMake package.
set(_cmakedir ${CMAKE_INSTALL_LIBDIR}/cmake/floesim)
install(EXPORT floesimTargets NAMESPACE floesim:: DESTINATION ${_cmakedir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/floesimConfig.cmake.in
  ${PROJECT_BINARY_DIR}/floesimConfig.cmake INSTALL_DESTINATION ${_cmakedir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/floesimConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/floesimConfig.cmake ${PROJECT_BINARY_DIR}/floesimConfigVersion.cmake
  DESTINATION ${_cmakedir})

# pkg-config: paths relative to the .pc file's folder, so the install can be
# moved (or made with --prefix) after configuring.
file(RELATIVE_PATH _pc_to_prefix /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
string(REGEX REPLACE "/$" "" _pc_to_prefix "${_pc_to_prefix}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/floesim.pc.in ${PROJECT_BINARY_DIR}/floesim.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/floesim.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# The man page, made from the tool's own --help texts after each build of it.
set(_man ${PROJECT_BINARY_DIR}/man/floesim.1)
add_custom_command(OUTPUT ${_man}
  COMMAND ${CMAKE_COMMAND} -DFLOESIM=$<TARGET_FILE:floesim> -DOUT=${_man} -DVERSION=${PROJECT_VERSION}
          -P ${PROJECT_SOURCE_DIR}/cmake/floesim_man.cmake
  DEPENDS floesim ${PROJECT_SOURCE_DIR}/cmake/floesim_man.cmake
  COMMENT "Writing the floesim(1) man page from --help"
  VERBATIM)
add_custom_target(floesim_man ALL DEPENDS ${_man})
install(FILES ${_man} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)

# Examples and the data they read, side by side as in the sources, so that the
# relative paths inside the examples (../data/...) still hold; the installed
# tool's `floesim run` with no file runs share/floesim/examples/floes_on_waves.toml.
install(DIRECTORY examples data DESTINATION ${CMAKE_INSTALL_DATADIR}/floesim)
install(FILES README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR})
