# Writes the floesim(1) man page from the tool's own help texts, so that the
# page says exactly what `floesim --help` and `floesim SUBCOMMAND --help` say.
#   cmake -DFLOESIM=path/to/floesim -DOUT=floesim.1 -DVERSION=x.y.z -P floesim_man.cmake

function(help_of out)
  execute_process(COMMAND ${FLOESIM} ${ARGN} --help OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "floesim ${ARGN} --help exited ${rc}")
  endif()
  # The usage line names the binary by the path it was run from: use its name.
  string(REPLACE "${FLOESIM}" "floesim" text "${text}")
  # Roff: a backslash is \e; a line starting with . or ' is guarded by \&.
  string(REPLACE "\\" "\\e" text "${text}")
  string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

help_of(main)
# The subcommands are the indented names under "Subcommands:".
string(REGEX MATCH "Subcommands:\n(.*)" section "${main}")
string(REGEX MATCHALL "\n  [a-z]+ " names "\n${CMAKE_MATCH_1}\n")
set(subcommands)
foreach(n IN LISTS names)
  string(STRIP "${n}" n)
  list(APPEND subcommands ${n})
endforeach()
if(NOT subcommands)
  message(FATAL_ERROR "no subcommands found in floesim --help")
endif()

string(TIMESTAMP date "%Y-%m-%d" UTC)
set(page ".TH FLOESIM 1 \"${date}\" \"floesim ${VERSION}\" \"User Commands\"
.SH NAME
floesim \\- sea-ice floes on waves: rigid floes, Lemke collisions, a penalised capillary-gravity sea
.SH SYNOPSIS
.B floesim
.I SUBCOMMAND
[\\fIOPTIONS\\fR]
.SH DESCRIPTION
.nf
${main}.fi
.SH SUBCOMMANDS
")
foreach(sub IN LISTS subcommands)
  help_of(text ${sub})
  string(APPEND page ".SS ${sub}\n.nf\n${text}.fi\n")
endforeach()
string(APPEND page ".SH EXIT STATUS
0 success; 1 the run failed numerically (or, for compare, lcp and regress, a
negative answer: see each subcommand); 2 bad input or usage; 130 interrupted.
.SH FILES
.I share/floesim/examples
(the example scenarios),
.I share/floesim/data
(the data they read), and the documentation in
.IR share/doc/floesim ,
under the install prefix.
")
file(WRITE ${OUT} "${page}")
