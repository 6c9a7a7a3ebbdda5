#!/usr/bin/env bash
# scripts/fetch_data.sh without the network: the manifest's SHA-256 sums match the data
# folder the tests read; a fetch from a mirror folder fills a new data folder that then
# checks, and a second fetch downloads nothing; a corrupted file is refused with nothing
# half-written left; an unreachable source says what to do offline.
# Usage: tests/fetch_data_test.sh SOURCE_DIR DATA_DIR   (MGRL_DATA, when set, for DATA_DIR)
set -euo pipefail
source="$(cd "$1" && pwd)"
data="$(cd "${MGRL_DATA:-$2}" && pwd)"
fetch="$source/scripts/fetch_data.sh"
work="$(mktemp -d /tmp/mgrl-fetch-test.XXXXXX)"
trap 'rm -rf "$work"' EXIT
fail() {
  echo "fetch_data_test: FAIL: $*" >&2
  exit 1
}

bash "$fetch" --check "$data" --bandai >"$work/check.log" 2>&1 || { cat "$work/check.log" >&2; fail "the sums against $data"; }
echo "ok   - $(tail -1 "$work/check.log")"

bash "$fetch" --from "$data" "$work/user/mgrl" >"$work/fetch.log" 2>&1 || { tail "$work/fetch.log" >&2; fail "a fetch from $data"; }
[ ! -e "$work/user/mgrl.download" ] || fail "the folder filled under another name was left behind"
bash "$fetch" --check "$work/user/mgrl" >/dev/null 2>&1 || fail "the fetched folder does not check"
[ -f "$work/user/mgrl/cmu/asfamc/13_17.amc" ] || fail "expected cmu/asfamc/13_17.amc fetched"
[ ! -e "$work/user/mgrl/bandai_namco_1" ] || fail "fetched the Bandai Namco library without --bandai"
bash "$fetch" --from "$data" "$work/user/mgrl" >"$work/again.log" 2>&1 || fail "a second fetch"
grep -q "^fetch_data: 0 downloaded" "$work/again.log" || fail "a second fetch downloaded again: $(tail -1 "$work/again.log")"
echo "ok   - a fetch from a mirror fills a new folder that checks; a second one downloads nothing"

# A mirror with one corrupted file.
cp -rs "$data" "$work/mirror"
rm "$work/mirror/cmu/asfamc/13.asf"
sed 's/0.45/0.46/' "$data/cmu/asfamc/13.asf" >"$work/mirror/cmu/asfamc/13.asf"
if bash "$fetch" --from "$work/mirror" "$work/other/mgrl" >"$work/bad.log" 2>&1; then fail "a corrupted file was accepted"; fi
grep -q "cmu/asfamc/13.asf: expected SHA-256" "$work/bad.log" ||
  grep -q "expected SHA-256 .* for cmu/asfamc/13.asf" "$work/bad.log" || { cat "$work/bad.log" >&2; fail "the refusal names no file"; }
[ ! -e "$work/other/mgrl" ] || fail "a refused fetch left the data folder mgrl would read"
[ -z "$(find "$work/other" -name '*.part-*')" ] || fail "a refused fetch left a partial file"
echo "ok   - a corrupted file is refused, and mgrl's folder is not made"

if bash "$fetch" --from "file:///nonexistent-mirror" "$work/offline/mgrl" >"$work/offline.log" 2>&1; then
  fail "a fetch from nowhere passed"
fi
grep -q "Offline?" "$work/offline.log" || { cat "$work/offline.log" >&2; fail "no word of what to do offline"; }
echo "ok   - an unreachable source says what to do offline"

# A file with no public home (no URL) is not downloaded without --from: the new folder is not
# put in place, so that mgrl does not read it by default without that file.
{
  printf 'relative_path\tsha256\turl\tverified\tnote\n'
  printf 'cmu/asfamc/13.asf\t%s\tfile://%s\tyes\tread from the data folder\n' \
    "$(sha256sum "$data/cmu/asfamc/13.asf" | cut -d' ' -f1)" "$data/cmu/asfamc/13.asf"
  printf 'cmu/bvh/13_17_boxing.bvh\t%s\t\tno\tconverted locally\n' \
    "$(sha256sum "$data/cmu/bvh/13_17_boxing.bvh" | cut -d' ' -f1)"
} >"$work/manifest.tsv"
status=0
MGRL_FETCH_MANIFEST="$work/manifest.tsv" bash "$fetch" "$work/homeless/mgrl" >"$work/homeless.log" 2>&1 || status=$?
[ "$status" -eq 3 ] || { cat "$work/homeless.log" >&2; fail "expected exit status 3 with a file that has no URL, found $status"; }
grep -q "no public home.*cmu/bvh/13_17_boxing.bvh" "$work/homeless.log" || fail "the file with no public home is not named"
[ -f "$work/homeless/mgrl.download/cmu/asfamc/13.asf" ] || fail "the downloadable file was not fetched"
[ ! -e "$work/homeless/mgrl" ] || fail "an incomplete folder was put where mgrl reads by default"
MGRL_FETCH_MANIFEST="$work/manifest.tsv" bash "$fetch" --from "$data" "$work/homeless/mgrl" >/dev/null 2>&1 ||
  fail "completing the folder with --from"
[ -f "$work/homeless/mgrl/cmu/bvh/13_17_boxing.bvh" ] || fail "--from did not complete the folder"
echo "ok   - a file with no public home keeps the folder out of mgrl's way until --from completes it"

cp "$work/mirror/cmu/asfamc/13.asf" "$work/user/mgrl/cmu/asfamc/13.asf"
if bash "$fetch" --check "$work/user/mgrl" >"$work/recheck.log" 2>&1; then fail "--check passed a corrupted folder"; fi
grep -q "13.asf: expected SHA-256" "$work/recheck.log" || fail "--check names no file: $(cat "$work/recheck.log")"
echo "ok   - --check names a corrupted file"
# Wrong arguments: one line each, saying what was expected.
status=0
bash "$fetch" --check "$work/no-such-folder" >"$work/args.log" 2>&1 || status=$?
if ! { [ "$status" -eq 2 ] && grep -q "expected a data folder, found no folder" "$work/args.log"; }; then
  fail "--check on a missing folder: status $status, $(cat "$work/args.log")"
fi
status=0
bash "$fetch" --bogus >"$work/args.log" 2>&1 || status=$?
if ! { [ "$status" -eq 2 ] && grep -q "unknown option --bogus (expected" "$work/args.log"; }; then
  fail "an unknown option: status $status, $(cat "$work/args.log")"
fi
status=0
MGRL_FETCH_MANIFEST="$work/none.tsv" bash "$fetch" --check "$data" >"$work/args.log" 2>&1 || status=$?
if ! { [ "$status" -eq 2 ] && grep -q "expected the list of files and sums in $work/none.tsv, found none" "$work/args.log"; }; then
  fail "a missing manifest: status $status, $(cat "$work/args.log")"
fi
echo "ok   - a missing folder, an unknown option and a missing manifest are refused with what was expected"
echo "fetch_data_test: all passed"
