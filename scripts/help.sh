#!/usr/bin/env bash
# Sourced by every script of scripts/ before it does anything: with -h or --help as the first
# argument it prints the script's header comment (what it does, its usage) and exits 0, so that
# asking for help never starts a build.
# Usage: source "$(dirname "$0")/help.sh"   (in a script, after its header comment)
case "${1:-}" in
  -h | --help)
    sed -n '2,/^[^#]/s/^# \{0,1\}//p' "$0"
    exit 0
    ;;
esac
