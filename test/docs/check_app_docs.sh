#!/usr/bin/env bash
# Every app has its page in doc/apps/ and every option an app's --help lists is named on
# its page (or in the shared-flags table of doc/apps/README.md); a page without a built app
# is only noted (agex may be built without its 2D apps).
# Usage: check_app_docs.sh BIN_DIR SOURCE_DIR
set -u
bin_dir=$1
doc_dir=$2/doc/apps
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

apps=()
for exe in "$bin_dir"/agex_*; do
  name=$(basename "$exe")
  case $name in agex_test_* | agex_fuzz_*) continue ;; esac
  [ -x "$exe" ] && apps+=("$name")
done
[ ${#apps[@]} -gt 0 ] || { echo "FAIL: no apps in $bin_dir"; exit 1; }

for page in "$doc_dir"/agex_*.md; do
  name=$(basename "$page" .md)
  [ -x "$bin_dir/$name" ] || echo "note: $page has no built app (built without it?)"
done

for app in "${apps[@]}"; do
  page=$doc_dir/$app.md
  if [ ! -f "$page" ]; then
    fail "$app has no page $page"
    continue
  fi
  grep -q "^# $app\$" "$page" || fail "$page does not start with '# $app'"
  grep -q "\[$app\]($app.md)" "$doc_dir/README.md" || fail "doc/apps/README.md does not link $app.md"
  # Apps with subcommands list each one's options under "APP SUB --help".
  case $app in
    agex_annotate) subcommands="coco masks rgbd" ;;
    agex_convert) subcommands="bonn u16 pcd" ;;
    agex_eval) subcommands="coverage detect compare" ;;
    *) subcommands="" ;;
  esac
  # Option lines of Boost.Program_options' help: "  --name arg   text" or "  -h [ --help ]".
  options=$( { "$bin_dir/$app" --help 2>&1; for sub in $subcommands; do "$bin_dir/$app" "$sub" --help 2>&1; done; } |
    sed -n 's/^  \(-[a-z] \[ \)\{0,1\}--\([a-z0-9][a-z0-9-]*\).*/\2/p' | sort -u)
  # A page may defer flags to another app's page it links ("the trainer flags are those of ...").
  linked=$(grep -o '(agex_[a-z_]*\.md)' "$page" | tr -d '()' | sort -u | sed "s#^#$doc_dir/#")
  [ -n "$options" ] || fail "$app --help lists no options"
  for option in $options; do
    # The positional arguments (INPUT..., MODE) appear in --help under these names.
    case $option in help | input | mode) continue ;; esac
    # The whole option name (not a prefix of a longer one), on the page, a page it defers
    # to, or in the shared-flags table of the index.
    pattern="--$option([^a-z0-9-]|\$)"
    grep -q -E -e "$pattern" "$page" $linked || grep '^|' "$doc_dir/README.md" | grep -q -E -e "$pattern" ||
      fail "$app --$option is not documented in $page"
  done
done

if [ $failures -gt 0 ]; then
  echo "$failures problem(s)"
  exit 1
fi
echo "checked ${#apps[@]} apps against doc/apps/"
