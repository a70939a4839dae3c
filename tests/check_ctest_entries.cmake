# Every ctest entry must run something. Run by ctest itself (tests/CMakeLists.txt,
# fuzz/CMakeLists.txt) as
#   cmake -D CTEST=<ctest> -D BUILD_DIR=<build dir> [-D LABEL=<regex>] -P check_ctest_entries.cmake
# It lists the entries of BUILD_DIR (only those labelled LABEL when given) and
# fails, naming each offender, when
#   - an entry's name contains ';' (ctest and CMake lists split names there);
#   - a Catch2 entry (label catch2) does not select exactly one test case of its
#     executable: its own command line plus --list-test-names-only is asked, so
#     the filter is matched by Catch2 itself, escapes and wildcards included;
#   - a Catch2 entry runs without -w NoTests (a filter matching nothing would
#     then print "No tests ran" and exit 0);
#   - a test case of a Catch2 executable has ';' in its name or is run by no
#     entry (catch_discover_tests splits such a name into pieces that match
#     nothing);
#   - a fuzz entry (label fuzz) has no executable or an empty seed corpus (its
#     last argument);
#   - an entry has none of the labels catch2, fuzz, script (a program that is one
#     test case on its own) or suite-check (this check), so a new kind of entry
#     has to say how it is checked.
cmake_minimum_required(VERSION 3.25)

if(NOT CTEST OR NOT BUILD_DIR)
  message(FATAL_ERROR "usage: cmake -D CTEST=<ctest> -D BUILD_DIR=<dir> [-D LABEL=<regex>] -P ${CMAKE_CURRENT_LIST_FILE}")
endif()

set(label_args)
if(LABEL)
  set(label_args -L "${LABEL}")
endif()
execute_process(COMMAND "${CTEST}" --test-dir "${BUILD_DIR}" --show-only=json-v1 ${label_args}
                OUTPUT_VARIABLE listing ERROR_VARIABLE listing_err RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "ctest --show-only=json-v1 failed (${rc}): ${listing_err}")
endif()

set(problems "")
function(problem text)  # a function, not a macro: names may hold '\' (Catch2 escapes)
  set(problems "${problems}  - ${text}\n" PARENT_SCOPE)
endfunction()

# Names go into CMake lists, which split on ';' and not inside '[...]': in
# lists they are kept with those three characters replaced by markers.
function(list_safe out text)
  string(REPLACE ";" "<semicolon>" text "${text}")
  string(REPLACE "[" "<{" text "${text}")
  string(REPLACE "]" "}>" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()
function(shown out text)
  string(REPLACE "<semicolon>" ";" text "${text}")
  string(REPLACE "<{" "[" text "${text}")
  string(REPLACE "}>" "]" text "${text}")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

# The non-empty lines of a program's output, as a list of list-safe names.
function(lines_of out text)
  list_safe(text "${text}")
  string(REPLACE "\r" "" text "${text}")
  string(REPLACE "\n" ";" text "${text}")
  list(REMOVE_ITEM text "")
  set(${out} "${text}" PARENT_SCOPE)
endfunction()

string(JSON count LENGTH "${listing}" tests)
set(executables "")
set(checked_catch 0)
set(checked_fuzz 0)
set(checked_script 0)
if(count GREATER 0)
  math(EXPR last "${count} - 1")
  foreach(i RANGE ${last})
    # One entry's JSON first: string(JSON) parses its whole input on every call.
    string(JSON entry GET "${listing}" tests ${i})
    string(JSON name GET "${entry}" name)
    if(name MATCHES ";")
      problem("'${name}': the name contains ';'")
    endif()

    # Labels and the command line.
    set(labels "")
    string(JSON nprops ERROR_VARIABLE err LENGTH "${entry}" properties)
    if(NOT err AND nprops GREATER 0)
      math(EXPR plast "${nprops} - 1")
      foreach(p RANGE ${plast})
        string(JSON pname GET "${entry}" properties ${p} name)
        if(pname STREQUAL "LABELS")
          string(JSON nl LENGTH "${entry}" properties ${p} value)
          math(EXPR llast "${nl} - 1")
          foreach(l RANGE ${llast})
            string(JSON lv GET "${entry}" properties ${p} value ${l})
            list(APPEND labels "${lv}")
          endforeach()
        endif()
      endforeach()
    endif()
    string(JSON nargs ERROR_VARIABLE err LENGTH "${entry}" command)
    if(NOT err AND nargs GREATER 0)
      math(EXPR alast "${nargs} - 1")
      foreach(a RANGE ${alast})
        string(JSON arg_${a} GET "${entry}" command ${a})
      endforeach()
    else()
      set(nargs 0)
    endif()

    if("suite-check" IN_LIST labels)
      # This check (or its scoped twin): nothing to run.
    elseif(nargs EQUAL 0)
      # ctest leaves the command out when it cannot find the executable.
      problem("'${name}': no command: its executable is not built")
    elseif("catch2" IN_LIST labels)
      math(EXPR checked_catch "${checked_catch} + 1")
      if(nargs LESS 2)
        problem("'${name}': a Catch2 entry without a test filter")
        continue()
      endif()
      set(exe "${arg_0}")
      set(args "")
      set(has_nowarn FALSE)
      math(EXPR alast "${nargs} - 1")
      foreach(a RANGE 1 ${alast})
        # execute_process takes the arguments from a list, which a ';' would split.
        if(arg_${a} MATCHES ";")
          problem("'${name}': argument '${arg_${a}}' contains ';'")
        endif()
        list(APPEND args "${arg_${a}}")
        if(a GREATER 1 AND arg_${a} STREQUAL "NoTests")
          math(EXPR prev "${a} - 1")
          if(arg_${prev} STREQUAL "-w" OR arg_${prev} STREQUAL "--warn")
            set(has_nowarn TRUE)
          endif()
        endif()
      endforeach()
      if(NOT has_nowarn)
        problem("'${name}': runs without '-w NoTests' (register Catch2 tests with homing_catch_tests())")
      endif()
      if(NOT EXISTS "${exe}")
        problem("'${name}': executable ${exe} is not built")
        continue()
      endif()
      execute_process(COMMAND "${exe}" ${args} --list-test-names-only OUTPUT_VARIABLE selected ERROR_QUIET)
      if(selected MATCHES ";")
        problem("'${name}': its filter selects a test case whose name contains ';'")
      endif()
      lines_of(selected "${selected}")
      list(LENGTH selected n)
      if(NOT n EQUAL 1)
        string(REPLACE ";" " | " which "${selected}")
        shown(which "${which}")
        problem("'${name}': its filter '${arg_1}' selects ${n} test cases of ${exe}, not exactly one (${which})")
      endif()
      string(MAKE_C_IDENTIFIER "${exe}" key)
      if(NOT "${exe}" IN_LIST executables)
        list(APPEND executables "${exe}")
        set(covered_${key} "")
      endif()
      list(APPEND covered_${key} ${selected})
    elseif("fuzz" IN_LIST labels)
      math(EXPR checked_fuzz "${checked_fuzz} + 1")
      math(EXPR alast "${nargs} - 1")
      if(nargs LESS 2)
        problem("'${name}': a fuzz entry without a seed corpus argument")
        continue()
      endif()
      if(NOT EXISTS "${arg_0}")
        problem("'${name}': executable ${arg_0} is not built")
      endif()
      file(GLOB seeds "${arg_${alast}}/*")
      if(NOT IS_DIRECTORY "${arg_${alast}}" OR NOT seeds)
        problem("'${name}': its seed corpus ${arg_${alast}} is missing or empty")
      endif()
    elseif("script" IN_LIST labels)
      math(EXPR checked_script "${checked_script} + 1")
    else()
      problem("'${name}': labelled none of catch2, fuzz, script, suite-check; say how this entry runs a test")
    endif()
  endforeach()
endif()

# Every test case of every Catch2 executable is run by some entry, and none has
# ';' in its name.
foreach(exe IN LISTS executables)
  string(MAKE_C_IDENTIFIER "${exe}" key)
  execute_process(COMMAND "${exe}" --list-test-names-only OUTPUT_VARIABLE all ERROR_QUIET)
  lines_of(all "${all}")
  foreach(test IN LISTS all)
    shown(name "${test}")
    if(test MATCHES "<semicolon>")
      problem("test case '${name}' of ${exe}: the name contains ';' (ctest discovery splits it into pieces that run nothing)")
    endif()
    list(FIND covered_${key} "${test}" found)
    if(found EQUAL -1)
      problem("test case '${name}' of ${exe} is run by no ctest entry")
    endif()
  endforeach()
endforeach()

if(problems)
  message(FATAL_ERROR "ctest entries that run no test case, or not exactly one:\n${problems}")
endif()
message(STATUS "${count} ctest entries checked: ${checked_catch} Catch2 entries select exactly one test case each"
               " (-w NoTests), ${checked_fuzz} fuzz entries have a seed corpus, ${checked_script} script entries")
