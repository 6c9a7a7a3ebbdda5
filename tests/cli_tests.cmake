# CLI tests (label "cli"): the real `mgrl` binary on the files in tests/data, run through
# run_cli.cmake so that the exit code and the streams are checked as well as the text
# (PASS_REGULAR_EXPRESSION alone ignores the exit code). The tests run inside tests/data,
# so messages name the files as given: `truncated.bvh:12: expected ..., found ...`.

set(MGRL_CLI_DATA "${CMAKE_CURRENT_SOURCE_DIR}/data")
set(MGRL_CLI_RUNNER "${CMAKE_CURRENT_SOURCE_DIR}/run_cli.cmake")

# `literal` as a regular expression matching exactly that text.
function(mgrl_regex_escape out literal)
  string(REGEX REPLACE "([][+.*?()^$|\\\\{}])" "\\\\\\1" escaped "${literal}")
  set(${out} "${escaped}" PARENT_SCOPE)
endfunction()

# mgrl_cli_test(<name> ARGS <arg>... [EXIT nonzero|<code>] [JSON]
#               (MESSAGE <exact stderr text after "mgrl: "> | REGEX <regex> | STDOUT <regex>))
#   MESSAGE: the error line must be exactly "mgrl: <text>" (text taken literally).
#   REGEX:   the error line must start with "mgrl: " and then match <regex>.
#   STDOUT:  success; stdout must match <regex> from its start (begin with .* to search).
# Texts must not contain ';' (CMake would split them into a list).
function(mgrl_cli_test name)
  cmake_parse_arguments(PARSE_ARGV 1 arg "JSON" "EXIT;MESSAGE;REGEX;STDOUT" "ARGS")
  list(JOIN arg_ARGS "|" joined)
  if(DEFINED arg_STDOUT)
    set(exit 0)
    set(pass "run_cli ok: stdout=<${arg_STDOUT}")
  else()
    set(exit nonzero)
    if(DEFINED arg_MESSAGE)
      mgrl_regex_escape(escaped "${arg_MESSAGE}")
      set(pass "run_cli ok: stderr=<mgrl: ${escaped}>")
    else()
      set(pass "run_cli ok: stderr=<mgrl: ${arg_REGEX}")
    endif()
  endif()
  if(DEFINED arg_EXIT)
    set(exit "${arg_EXIT}")
  endif()
  add_test(NAME cli_${name}
           COMMAND ${CMAKE_COMMAND} "-DMGRL=$<TARGET_FILE:mgrl>" "-DARGS=${joined}" "-DWORKDIR=${MGRL_CLI_DATA}"
                   "-DEXIT=${exit}" "-DJSON=${arg_JSON}" -P "${MGRL_CLI_RUNNER}")
  set_tests_properties(cli_${name} PROPERTIES LABELS cli PASS_REGULAR_EXPRESSION "${pass}")
endfunction()

# --- Success -------------------------------------------------------------------------

mgrl_regex_escape(version_regex "mgrl ${PROJECT_VERSION}")
mgrl_cli_test(version ARGS --version STDOUT "${version_regex}\n>")
mgrl_cli_test(help ARGS --help STDOUT ".*inspect")
mgrl_cli_test(inspect_json ARGS inspect tiny.bvh --json JSON STDOUT ".*\"effective_hits\"")
mgrl_cli_test(inspect_text ARGS inspect tiny.bvh STDOUT "tiny\\.bvh\n  joints 16, frames 4 at 30 fps")

# --- Broken files: one line `file:line: expected ..., found ...`, exit 1 -----------------

mgrl_cli_test(truncated_bvh ARGS inspect truncated.bvh EXIT 1
  MESSAGE "truncated.bvh:12: expected OFFSET, CHANNELS, JOINT, End Site or '}', found end of file")
mgrl_cli_test(bad_channel_count_bvh ARGS inspect bad_channel_count.bvh EXIT 1
  MESSAGE "bad_channel_count.bvh:25: expected 12 channel values, found 11")
mgrl_cli_test(nan_bvh ARGS inspect nan.bvh EXIT 1
  MESSAGE "nan.bvh:24: expected a finite number, found 'nan'")
mgrl_cli_test(no_motion_bvh ARGS inspect no_motion.bvh EXIT 1
  MESSAGE "no_motion.bvh:20: expected 'MOTION', found end of file")
mgrl_cli_test(zero_frame_time_bvh ARGS inspect zero_frame_time.bvh EXIT 1
  MESSAGE "zero_frame_time.bvh:23: expected a positive frame time, found 0")
mgrl_cli_test(duplicate_joint_bvh ARGS inspect duplicate_joint.bvh EXIT 1
  MESSAGE "duplicate_joint.bvh:10: expected a unique joint name, found 'Chest' again (first on line 6)")
mgrl_cli_test(absurd_frame_count_bvh ARGS inspect absurd_frame_count.bvh EXIT 1
  MESSAGE "absurd_frame_count.bvh:22: expected a frame count between 0 and 10000000, found '99999999999'")
# cycle_01.amc is fine; its skeleton cycle.asf (found by subject prefix) is not.
mgrl_cli_test(cycle_asf ARGS inspect cycle_01.amc EXIT 1
  MESSAGE "cycle.asf:51: expected a tree rooted at root, found a cycle through 'lfemur'")
mgrl_cli_test(unknown_bone_amc ARGS inspect tiny_02.amc EXIT 1
  MESSAGE "tiny_02.amc:7: expected a bone of the skeleton, found 'lknee'")
# A bad file after a good one: still nothing on stdout.
mgrl_cli_test(good_then_bad ARGS inspect tiny.bvh nan.bvh --json EXIT 1
  MESSAGE "nan.bvh:24: expected a finite number, found 'nan'")

# --- Other input errors, exit 1 -------------------------------------------------------------

mgrl_cli_test(missing_file ARGS inspect nope.bvh EXIT 1
  REGEX "nope\\.bvh: cannot open: [^>]+>")
mgrl_cli_test(unknown_extension ARGS inspect ../cli_tests.cmake EXIT 1
  MESSAGE "../cli_tests.cmake: expected a .bvh or .amc file, found extension '.cmake'")
mgrl_cli_test(asf_instead_of_amc ARGS inspect tiny.asf EXIT 1
  REGEX "tiny\\.asf: expected a motion \\(\\.bvh or \\.amc\\), found an ASF skeleton")
mgrl_cli_test(amc_without_asf ARGS inspect nope_01.amc EXIT 1
  REGEX "nope_01\\.amc: expected its skeleton nope\\.asf, found no such file")
mgrl_cli_test(units_furlong ARGS inspect tiny.bvh --units furlong EXIT 1
  MESSAGE "--units: expected one of auto, m, cm, inch, cmu, found 'furlong'")
mgrl_cli_test(unknown_command ARGS frobnicate EXIT 2
  REGEX "expected a command \\(inspect, init, graph, train, eval, simulate, compare, serve, stats, list\\), found 'frobnicate'")

# --- Usage errors, exit 2 -----------------------------------------------------------------

mgrl_cli_test(no_subcommand ARGS EXIT 2 REGEX "[^>]*\\(see mgrl --help\\)>")
mgrl_cli_test(inspect_without_file ARGS inspect EXIT 2 REGEX "FILE is required")

# --- Option values, exit 1 ---------------------------------------------------------------

mgrl_cli_test(fps_negative ARGS inspect tiny.bvh --fps -3 EXIT 1
  MESSAGE "--fps: expected a frame rate in (0, 10000], found -3")
mgrl_cli_test(role_without_joint ARGS inspect tiny.bvh --role left_fist EXIT 1
  MESSAGE "--role: expected ROLE=JOINT, found 'left_fist'")
mgrl_cli_test(role_unknown_joint ARGS inspect tiny.bvh --role left_fist=Nope EXIT 1
  REGEX "tiny\\.bvh: role left_fist: expected a joint of the skeleton, found 'Nope'")

# --- mgrl graph ------------------------------------------------------------------------
mgrl_cli_test(graph_unknown_key ARGS graph bad_scenario.yaml
              MESSAGE "bad_scenario.yaml:5:13: graph.treshold: unknown key (expected one of: threshold, velocity_weight, root_height_weight, contact_event, local_minimum, blend_frames, min_states, joint_weights, threads, max_out_degree, standing_cuts)")
mgrl_cli_test(graph_missing_scenario ARGS graph no_such.yaml MESSAGE "no_such.yaml: cannot open: No such file or directory")
mgrl_cli_test(graph_no_scenario ARGS graph EXIT 2 REGEX "SCENARIO is required")

# --- What a new user types ---------------------------------------------------------------

# An unknown option gets the nearest known one; --behaviour is --behavior.
mgrl_cli_test(unknown_option_nearest ARGS eval tiny.bvh --contoller random EXIT 2
              MESSAGE "eval: unknown option --contoller (did you mean --controller?)")
mgrl_cli_test(unknown_option_far ARGS simulate tiny.bvh --frobnicate EXIT 2
              MESSAGE "simulate: unknown option --frobnicate (see mgrl simulate --help)")
mgrl_cli_test(behaviour_spelling ARGS train "${MGRL_SOURCE_DIR}/scenarios/boxing.yaml" --behaviour nope
              MESSAGE "--behavior: expected one of the scenario's behaviours (approach, hit), found 'nope'")
# A value set with --set is reported at the flag, not at the file's line (which holds another).
mgrl_cli_test(set_names_flag ARGS train "${MGRL_SOURCE_DIR}/scenarios/boxing.yaml" --set world.mode=target
              MESSAGE "--set world.mode=target: world.mode: expected one of: sparring, targets, found 'target'")
mgrl_cli_test(set_names_flag_number ARGS eval "${MGRL_SOURCE_DIR}/scenarios/boxing.yaml"
              --set behaviors.hit.learner.budget=abc
              MESSAGE "--set behaviors.hit.learner.budget=abc: behaviors.hit.learner.budget: expected a whole number in [1, 1000000000000], found 'abc'")
# `mgrl graph` checks the behaviours too, as train would.
mgrl_cli_test(graph_checks_behaviours ARGS graph "${MGRL_SOURCE_DIR}/scenarios/boxing.yaml"
              --set behaviors.hit.learner.type=nope
              REGEX "--set behaviors\\.hit\\.learner\\.type=nope: behaviors\\.hit\\.learner\\.type: unknown learner 'nope'")

# A frame time no capture has (100000 s) is refused at its line, before
# resampling could ask for gigabytes.
mgrl_cli_test(huge_frame_time_bvh ARGS inspect huge_frame_time.bvh --fps 30 EXIT 1
  MESSAGE "huge_frame_time.bvh:13: expected a frame time of at most 1 s (1 fps), found 100000")
