# The install as a user gets it (ctest label install): `cmake --install` into
# an empty prefix, then
#   - the tool runs from there, its default example and the FloeDyn example
#     (which reads share/floesim/data) included;
#   - libfloesim.so carries its SONAME and version;
#   - a project outside floesim (this folder) finds it with find_package,
#     compiles every installed header, links, runs, and its floe drifts
#     downwind;
#   - pkg-config's flags compile and link the same program;
#   - the Python package imports from the prefix with PYTHONPATH alone;
#   - the man page has a section per subcommand;
#   - README.md's library example is main.cpp as it is.
# cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK=... -DCXX=... -DVERSION=...
#       [-DPYTHON=... -DPYTHONDIR=...] -P install_test.cmake

function(run)
  cmake_parse_arguments(R "" "OUT;DIR" "COMMAND" ${ARGN})
  execute_process(COMMAND ${R_COMMAND} WORKING_DIRECTORY ${R_DIR}
                  OUTPUT_VARIABLE out ERROR_VARIABLE err RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    list(JOIN R_COMMAND " " cmd)
    message(FATAL_ERROR "FAILED (exit ${rc}): ${cmd}\n${out}\n${err}")
  endif()
  if(R_OUT)
    set(${R_OUT} "${out}" PARENT_SCOPE)
  endif()
endfunction()

function(expect text regex what)
  if(NOT text MATCHES "${regex}")
    message(FATAL_ERROR "FAILED: ${what}: expected /${regex}/ in:\n${text}")
  endif()
  message(STATUS "ok: ${what}")
endfunction()

set(P ${WORK}/prefix)
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK}/run)

run(COMMAND ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${P} DIR ${WORK} OUT log)

# Where GNUInstallDirs put the library on this system (lib or lib64 or lib/<multiarch>).
file(GLOB_RECURSE libs ${P}/*/libfloesim.so)
list(LENGTH libs n)
if(NOT n EQUAL 1)
  message(FATAL_ERROR "FAILED: one libfloesim.so under ${P}, found: ${libs}")
endif()
get_filename_component(libdir ${libs} DIRECTORY)
string(REGEX MATCH "^([0-9]+)\\.([0-9]+)" _ ${VERSION})
set(soname libfloesim.so.${CMAKE_MATCH_1}.${CMAKE_MATCH_2})
foreach(f libfloesim.so ${soname} libfloesim.so.${VERSION})
  if(NOT EXISTS ${libdir}/${f})
    message(FATAL_ERROR "FAILED: ${libdir}/${f} not installed")
  endif()
endforeach()
run(COMMAND readelf -d ${libdir}/libfloesim.so.${VERSION} DIR ${WORK} OUT dyn)
expect("${dyn}" "SONAME[^\n]*\\[${soname}\\]" "SONAME ${soname}")

# The tool: version, the default example from share/floesim, the FloeDyn example.
run(COMMAND ${P}/bin/floesim --version DIR ${WORK}/run OUT v)
expect("${v}" "^${VERSION}" "floesim --version")
run(COMMAND ${P}/bin/floesim run -q --until 1 -o default.h5 DIR ${WORK}/run OUT v)
expect("${v}" "status: complete\nconfig: ${P}/share/floesim/examples/floes_on_waves.toml\n"
       "installed floesim run with no file runs the installed example")
run(COMMAND ${P}/bin/floesim run ${P}/share/floesim/examples/floedyn_100.toml -q --until 60 -o floedyn.h5
    DIR ${WORK}/run OUT v)
expect("${v}" "status: complete" "installed FloeDyn example reads the installed data")

# An outside project through find_package.
run(COMMAND ${CMAKE_COMMAND} -S ${SOURCE_DIR}/tests/install -B ${WORK}/outside
            -DCMAKE_PREFIX_PATH=${P} -DCMAKE_CXX_COMPILER=${CXX} -DCMAKE_BUILD_TYPE=Release
    DIR ${WORK})
run(COMMAND ${CMAKE_COMMAND} --build ${WORK}/outside DIR ${WORK})
set(floedyn_cfg ${P}/share/floesim/examples/floedyn_100.toml)
run(COMMAND ${WORK}/outside/uses_floesim ${floedyn_cfg} DIR ${WORK}/run OUT v)
message(STATUS "uses_floesim:\n${v}")
expect("${v}" "floes: 1\nt: 600\n" "one floe stepped to t = 600 s")
expect("${v}" "loaded_floes: 100\n" "the FloeDyn example loaded through the library")
string(REGEX MATCH "\ndx: ([^\n]+)\nvx: ([^\n]+)\n" _ "${v}")
# The floe starts at rest; a 15 m/s wind along +x moves it downwind.
if(NOT (CMAKE_MATCH_1 GREATER 1.0 AND CMAKE_MATCH_2 GREATER 0.01))
  message(FATAL_ERROR "FAILED: the floe did not drift downwind: dx = ${CMAKE_MATCH_1}, vx = ${CMAKE_MATCH_2}")
endif()
message(STATUS "ok: the floe drifted downwind (dx ${CMAKE_MATCH_1} m, vx ${CMAKE_MATCH_2} m/s)")

# pkg-config: the same program compiled and linked with its flags alone.
set(ENV{PKG_CONFIG_PATH} ${libdir}/pkgconfig)
run(COMMAND pkg-config --cflags floesim DIR ${WORK} OUT cflags)
run(COMMAND pkg-config --libs floesim DIR ${WORK} OUT libs)
run(COMMAND pkg-config --modversion floesim DIR ${WORK} OUT pcv)
expect("${pcv}" "^${VERSION}" "pkg-config --modversion")
separate_arguments(cflags UNIX_COMMAND "${cflags}")
separate_arguments(libs UNIX_COMMAND "${libs}")
run(COMMAND ${CXX} -std=c++20 -O1 ${cflags} ${SOURCE_DIR}/tests/install/main.cpp -o ${WORK}/uses_floesim_pc
            ${libs} -Wl,-rpath,${libdir}
    DIR ${WORK})
run(COMMAND ${WORK}/uses_floesim_pc DIR ${WORK}/run OUT v)
expect("${v}" "floes: 1\nt: 600\ndx: " "pkg-config build runs")

# README.md shows this main.cpp as it is.
file(READ ${SOURCE_DIR}/tests/install/main.cpp main_cpp)
file(READ ${SOURCE_DIR}/README.md readme)
string(FIND "${readme}" "```cpp\n${main_cpp}```" at)
if(at LESS 0)
  message(FATAL_ERROR "FAILED: README.md does not show tests/install/main.cpp as it is")
endif()
message(STATUS "ok: README.md shows tests/install/main.cpp")

# The Python package from the prefix alone.
if(PYTHON)
  set(ENV{PYTHONPATH} ${P}/${PYTHONDIR})
  # (No semicolons: the command goes through CMake lists.)
  set(code "import floesim, sys\nprint(floesim.__version__)\nprint(floesim.__file__)\n"
           "cfg = floesim.Config.load(sys.argv[1])\nprint(len(floesim.Simulation(cfg).state))\n")
  string(CONCAT code ${code})
  run(COMMAND ${PYTHON} -c "${code}" ${floedyn_cfg} DIR ${WORK}/run OUT v)
  expect("${v}" "^${VERSION}\n${P}/${PYTHONDIR}/floesim/__init__.py\n100\n" "import floesim from ${PYTHONDIR}")
endif()

# The man page: one section per subcommand of the installed tool.
file(READ ${P}/share/man/man1/floesim.1 man)
expect("${man}" "^\\.TH FLOESIM 1" "man page header")
foreach(sub compare fracture info lcp pack plot regress render run)
  expect("${man}" "\n\\.SS ${sub}\n\\.nf\n[^\n]*\nUsage: floesim ${sub}" "man page section ${sub}")
endforeach()
