# CLI tests of capture from elsewhere (label "cli"), on mgrl_cli_test from
# cli_tests.cmake: an AMC and an ASF that disagree are an error naming the line and bone,
# and a skeleton without finger joints loads.

# tiny_knee2.asf gives ltibia two degrees of freedom; tiny_01.amc gives it one value.
mgrl_cli_test(amc_asf_channel_mismatch ARGS inspect tiny_01.amc --asf tiny_knee2.asf EXIT 1
  MESSAGE "tiny_01.amc:6: expected 2 values for bone 'ltibia', found 1")
# tiny_foot.asf has a bone lfoot with a degree of freedom that tiny_01.amc never gives.
mgrl_cli_test(amc_asf_missing_bone ARGS inspect tiny_01.amc --asf tiny_foot.asf EXIT 1
  MESSAGE "tiny_01.amc:8: expected values for bone 'lfoot' in frame 1, found frame 2 starting")
# tiny_02.amc names a bone (lknee) that tiny.asf does not have.
mgrl_cli_test(amc_asf_unknown_bone ARGS inspect tiny_02.amc --asf tiny.asf EXIT 1
  MESSAGE "tiny_02.amc:7: expected a bone of the skeleton, found 'lknee'")
# No finger joints: the wrists' end sites are the fists (the warning is checked in
# cli_motion_test.cpp; here --json keeps stdout one object). Its left punch on the floor
# does not count.
mgrl_cli_test(inspect_without_fingers_json ARGS inspect boxer21.bvh --json --role left_fist=LeftWrist
  --role right_fist=RightWrist JSON STDOUT ".*\"punches\": {\n *\"left\": 1,")
