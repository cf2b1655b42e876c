#!/bin/sh
# Prints the IDL appendix of the VehicleService specification: the contents
# of every fenced code block after the "付録 IDL" heading, joined in order
# (the first block holds #ifndef and the types, the second the interface
# and #endif). Usage: extract-idl.sh SOURCE.txt > VehicleService.idl
set -e
[ $# -eq 1 ] || { echo "usage: $0 SPEC_SOURCE.txt" >&2; exit 2; }
LC_ALL=C awk '
	found && /^```/ { inblock = !inblock; blocks++; next }
	found && inblock { print }
	$0 == "付録 IDL" { found = 1 }
	END { if (!found || blocks < 4 || inblock) exit 1 }
' "$1"
