#!/bin/sh
# Starts omniNames, the CORBA naming service, the same way on the first run
# and on every run after (docs/corba.md):
#   tools/corba/names.sh [PORT [DATADIR]] [omniNames or omniORB options...]
# PORT defaults to 2809, DATADIR to /tmp/names. The folder is made when
# missing; where an earlier run left its data file, the service starts on it
# and keeps its names ("-always": "omniNames -start" alone refuses with "data
# file exists", and without -start it cannot make the first one). Runs in
# the foreground until a signal; its log goes to stderr, or -errlog FILE.
set -e
port=2809
dir=/tmp/names
case ${1-} in [0-9]*) port=$1; shift ;; esac
case ${1-} in -* | '') ;; *) dir=$1; shift ;; esac
mkdir -p "$dir"
exec omniNames -start "$port" -always -datadir "$dir" "$@"
