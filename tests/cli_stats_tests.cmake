# `mgrl stats` through the real binary (label "cli"), on the tiny bouts in tests/data/stats:
# success with --json and as text, --compare, and one line per bad input.

mgrl_cli_test(stats_json ARGS stats stats/stand --json JSON STDOUT ".*\"distance_m\": {\n +\"deciles\"")
mgrl_cli_test(stats_text ARGS stats stats/stand stats/walk STDOUT "stats: 2 bouts\n.*pooled")
mgrl_cli_test(stats_pattern ARGS stats stats/punch_near/fighter_*.bvh --punch-min-body-speed 0 --json JSON
  STDOUT ".*\"landed\": 1,")
# Strikes each way: one line per bout, each fighter's thrown, landed and blocked.
mgrl_cli_test(stats_each_way ARGS stats stats/punch_near --punch-min-body-speed 0
  STDOUT ".*landed by the stronger side +100\\.0 %\n.*each way, punch_near: fighter_1\\.bvh 1 thrown, 1 landed, 0 blocked \\| fighter_2\\.bvh 0 thrown, 0 landed, 0 blocked\n")
# Nothing landed: no stronger side, a dash (not "nan %").
mgrl_cli_test(stats_each_way_none_landed ARGS stats stats/punch_guarded --punch-min-body-speed 0
  STDOUT ".*landed by the stronger side +-\n.*each way, punch_guarded: fighter_1\\.bvh 1 thrown, 0 landed, 1 blocked")
mgrl_cli_test(stats_compare ARGS stats --json --compare stats/stand -- stats/walk stats/overlap JSON
  STDOUT ".*\"wasserstein1\": {\n +\"distance_m\": 0\\.[0-9]+")
mgrl_cli_test(stats_help ARGS --help STDOUT ".*stats")

mgrl_cli_test(stats_missing_folder ARGS stats stats/nowhere EXIT 1
  REGEX "stats/nowhere: expected a folder of BVH files or a quoted file pattern, found no such folder or file \\(looked in the working folder and in the data folder .*\\)")
mgrl_cli_test(stats_no_bvh ARGS stats stats/no_bvh EXIT 1
  MESSAGE "stats/no_bvh: expected BVH files in the folder (one per fighter), found none")
mgrl_cli_test(stats_pattern_matches_nothing ARGS stats stats/stand/zz_*.bvh EXIT 1
  REGEX "stats/stand/zz_\\*\\.bvh: expected files matching the pattern, found none")
mgrl_cli_test(stats_one_fighter ARGS stats stats/stand/fighter_1*.bvh EXIT 1
  MESSAGE "bout fighter_1*.bvh: expected at least 2 fighters (BVH files), found 1 (stats/stand/fighter_1.bvh)")
mgrl_cli_test(stats_mixed_frame_times ARGS stats stats/mixed_rate EXIT 1
  MESSAGE "bout mixed_rate: expected one frame time for all fighters, found 0.0333333 s in stats/mixed_rate/fighter_1.bvh and 0.0166667 s in stats/mixed_rate/fighter_2.bvh")
mgrl_cli_test(stats_malformed_bvh ARGS stats stats/broken EXIT 1
  MESSAGE "stats/broken/fighter_2.bvh:100: expected 6 channel values, found 5")
mgrl_cli_test(stats_compare_without_dash ARGS stats --compare stats/stand stats/walk EXIT 1
  MESSAGE "--compare: expected REAL... -- SYNTH..., found no '--'")
mgrl_cli_test(stats_dash_without_compare ARGS stats stats/stand -- stats/walk EXIT 1
  MESSAGE "stats: expected --compare before a '--' (mgrl stats --compare REAL... -- SYNTH...)")
mgrl_cli_test(stats_compare_nothing_after_dash ARGS stats --compare stats/stand -- EXIT 1
  MESSAGE "--compare: expected synthesized bouts after '--', found none")
mgrl_cli_test(stats_no_bout ARGS stats EXIT 1
  MESSAGE "stats: expected a BOUT (a folder or a quoted file pattern) or --snu, found none")
mgrl_cli_test(stats_option_after_dash ARGS stats --compare stats/stand -- stats/walk --json EXIT 1
  MESSAGE "--compare: expected options before '--', found '--json' after it")
mgrl_cli_test(stats_negative_land_radius ARGS stats stats/stand --land-radius=-1 EXIT 1
  MESSAGE "--land-radius: expected a distance >= 0 (m), found -1")
mgrl_cli_test(stats_negative_block_radius ARGS stats stats/stand --block-radius=-0.1 EXIT 1
  MESSAGE "--block-radius: expected a distance >= 0 (m), found -0.1")
