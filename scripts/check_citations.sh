#!/usr/bin/env bash
# Checks that every Markdown file the project cites exists in the repository, and every cited section
# `§N` (or range `§N–M`) of it has a heading `## N.`:  bash scripts/check_citations.sh [source-dir]
#
# A citation is any `<name>.md` or `<path>/<name>.md` in the text files of include/, tests/, examples/,
# bench/, scripts/, docs/, cmake/ and README.md (comments, strings and Markdown links alike). It must
# resolve from the repository's root or from the citing file's directory (Markdown links are relative).
# Prints every dangling citation as file:line and exits 1 if there is one. tests/docs runs it under ctest.
#
# One Perl process reads every file (perl-base is part of every Debian system): a process per citation,
# as this script once spawned, took half a minute of CI.
set -euo pipefail
root=$(cd "${1:-$(dirname "$0")/..}" && pwd)
cd "$root"

scan=()
for part in include tests examples bench scripts docs cmake README.md; do [ -e "$part" ] && scan+=("$part"); done
# The text files that mention .md at all, one per line, sorted: the files to read.
{ grep -rIl --exclude-dir=.git -P '\.md' "${scan[@]}" || true; } | LC_ALL=C sort | perl -e '
  use strict;
  use warnings;
  use File::Basename qw(dirname);
  # Bytes, not characters: § and – are matched as their UTF-8 bytes, and \w, \d, \s stay ASCII.
  # A path token ending in .md, not part of a URL or a <placeholder.md>, optionally followed by a section.
  my $citation = qr{(?<![\w/.:<-])((?:\.\./|[\w.-]+/)*[\w.-]+\.md)(?!\w)((?:[`)]?\s{0,2}§\s*\d+(?:\s*(?:–|-)\s*\d+)?)?)};
  my (%headings, $status);
  sub has_heading {    # whether $target has a heading "## N." (any level from 2), read once per file
    my ($target, $section) = @_;
    unless ($headings{$target}) {
      open(my $in, "<", $target) or die "cannot read $target: $!\n";
      $headings{$target} = { map { /^#{2,}\s+(\d+)\.(?:\s|$)/ ? ($1 => 1) : () } <$in> };
    }
    return $headings{$target}{$section};
  }
  sub complain { print STDERR "$_[0]: $_[1]\n"; $status = 1; }
  while (my $file = <STDIN>) {
    chomp $file;
    my $dir = dirname($file);
    open(my $in, "<", $file) or die "cannot read $file: $!\n";
    while (my $text = <$in>) {
      my %seen;    # a citation repeated on one line is checked once
      while ($text =~ /$citation/g) {
        my ($path, $sections) = ($1, $2);
        next if $seen{"$path$sections"}++;
        my $target = -f $path ? $path : -f "$dir/$path" ? "$dir/$path" : undef;
        unless (defined $target) {
          complain("$file:$.", "cites $path, which is not in the repository");
          next;
        }
        # The sections cited: §N, or both ends of §N–M.
        for my $section ($sections =~ /(\d+)/g) {
          complain("$file:$.", "cites $path §$section, but $target has no heading \x27## $section.\x27")
            unless has_heading($target, $section);
        }
      }
    }
  }
  exit($status ? 1 : 0);
'
echo "citations: every cited document and section exists"
