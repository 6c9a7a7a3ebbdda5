#!/usr/bin/env bash
# Downloads the motion capture mgrl's scenarios read (the CMU boxing, kata, walk and run
# takes; the SNU martial-arts sparring set; with --bandai the Bandai Namco library) from their
# public homes into the user's data folder, and checks each file's SHA-256 against
# scripts/mocap_sources.tsv. mgrl reads that folder by default once it exists.
#
#   scripts/fetch_data.sh [--bandai] [--from MIRROR] [DEST]   download what is missing or wrong
#   scripts/fetch_data.sh --check DIR                          check a data folder, no network
#
# Exit status 3: done, except files with no public home (the CMU takes' BVH conversions,
# listed without a URL in the manifest): copy them with --from.
# DEST: MGRL_DATA, else $XDG_DATA_HOME/mgrl, else ~/.local/share/mgrl. MIRROR: a folder or a
# URL holding the same layout (another machine's data folder), tried instead of the public
# homes. Licences: CMU (mocap.cs.cmu.edu; free for research and commercial use, do not resell
# the raw data), SNU/NCSOFT (BSD 3-Clause), Bandai Namco (CC BY-NC 4.0: non-commercial).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
manifest="${MGRL_FETCH_MANIFEST:-$root/scripts/mocap_sources.tsv}"
bandai=0
from=""
check=""
dest=""
while [ $# -gt 0 ]; do
  case "$1" in
    --bandai) bandai=1 ;;
    --from) from="${2:?fetch_data: --from needs a folder or URL}"; shift ;;
    --check) check="${2:?fetch_data: --check needs a folder}"; shift ;;
    -h | --help) sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "fetch_data: unknown option $1 (expected --bandai, --from MIRROR, --check DIR or a folder)" >&2; exit 2 ;;
    *) dest="$1" ;;
  esac
  shift
done
[ -f "$manifest" ] || { echo "fetch_data: expected the list of files and sums in $manifest, found none" >&2; exit 2; }

# The manifest's rows: path, SHA-256, URL, verified, note (a header line first; # starts a
# comment). An empty URL: the file has no public home (the CMU takes' BVH conversions).
rows() {
  # Tabs are whitespace to `read`: an empty URL would vanish, so it is printed as "-".
  awk -F'\t' -v bandai="$bandai" 'NR > 1 && $0 !~ /^#/ && NF >= 2 {
    if (bandai || $1 !~ /^bandai_namco_1\//) print $1 "\t" $2 "\t" ($3 == "" ? "-" : $3) }' "$manifest"
}

if [ -n "$check" ]; then
  [ -d "$check" ] || { echo "fetch_data: --check: expected a data folder, found no folder $check" >&2; exit 2; }
  bad=0
  total=0
  while IFS=$'\t' read -r path sum _; do
    total=$((total + 1))
    if [ ! -f "$check/$path" ]; then
      echo "fetch_data: $check/$path: missing" >&2
      bad=$((bad + 1))
    elif [ "$(sha256sum "$check/$path" | cut -d' ' -f1)" != "$sum" ]; then
      echo "fetch_data: $check/$path: expected SHA-256 $sum, found $(sha256sum "$check/$path" | cut -d' ' -f1)" >&2
      bad=$((bad + 1))
    fi
  done < <(rows)
  [ "$bad" -eq 0 ] || { echo "fetch_data: $bad of $total files missing or different in $check" >&2; exit 1; }
  echo "fetch_data: all $total files in $check match their SHA-256"
  exit 0
fi

if [ -z "$dest" ]; then
  if [ -n "${MGRL_DATA:-}" ]; then dest="$MGRL_DATA"
  elif [ -n "${XDG_DATA_HOME:-}" ]; then dest="$XDG_DATA_HOME/mgrl"
  else dest="${HOME:?fetch_data: expected HOME or a destination folder}/.local/share/mgrl"; fi
fi
command -v curl >/dev/null || { echo "fetch_data: expected curl (apt-get install curl), found none" >&2; exit 2; }
# A folder that does not exist yet is filled under another name and renamed when complete:
# mgrl reads the user's data folder as soon as it exists.
final="$dest"
if [ ! -d "$dest" ]; then
  dest="$final.download"
  mkdir -p "$dest"
fi
fetched=0
kept=0
homeless=()
while IFS=$'\t' read -r path sum url; do
  target="$dest/$path"
  if [ -f "$target" ] && [ "$(sha256sum "$target" | cut -d' ' -f1)" = "$sum" ]; then
    kept=$((kept + 1))
    continue
  fi
  source="$url"
  if [ -n "$from" ]; then
    case "$from" in *://*) source="${from%/}/$path" ;; *) source="file://$(cd "$from" && pwd)/$path" ;; esac
  elif [ "$url" = "-" ]; then
    homeless+=("$path")
    continue
  fi
  mkdir -p "$(dirname "$target")"
  partial="$target.part-$$"
  # A file is moved into place only once whole and checked: nothing half-written stays.
  if ! curl -fsSL --retry 2 --connect-timeout 20 -o "$partial" "$source"; then
    rm -f "$partial"
    echo "fetch_data: could not download $source for $path. Offline? Copy a data folder from a machine that has" \
      "one (scripts/fetch_data.sh --from THAT_FOLDER $final, or set MGRL_DATA to it), then check it with" \
      "scripts/fetch_data.sh --check $final; run this again to go on where it stopped" >&2
    exit 1
  fi
  got="$(sha256sum "$partial" | cut -d' ' -f1)"
  if [ "$got" != "$sum" ]; then
    rm -f "$partial"
    echo "fetch_data: $source: expected SHA-256 $sum for $path, found $got; nothing written" >&2
    exit 1
  fi
  mv "$partial" "$target"
  fetched=$((fetched + 1))
  echo "fetch_data: $path"
done < <(rows)
if [ "${#homeless[@]}" -gt 0 ]; then
  # Not renamed into place: mgrl would read a folder without them by default.
  echo "fetch_data: ${#homeless[@]} files have no public home to download from (the CMU takes' BVH conversions," \
    "which the boxing scenarios read, and the CMU licence summary): ${homeless[*]}" >&2
  echo "fetch_data: $fetched downloaded, $kept already there, in $dest; copy the rest from a data folder that has" \
    "them (scripts/fetch_data.sh --from THAT_FOLDER $final), or use this one as it is with MGRL_DATA=$dest" \
    "(the SNU scenarios: kick, sparring, walk_to)" >&2
  exit 3
fi
[ "$dest" = "$final" ] || mv "$dest" "$final"
echo "fetch_data: $fetched downloaded, $kept already there and correct, in $final (mgrl reads it by default" \
  "unless MGRL_DATA or --data says otherwise)"
