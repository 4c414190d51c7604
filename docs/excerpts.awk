# excerpts.awk -- writes a README again with every excerpt filled in from
# its source (docs/excerpts.sh runs it; see there). Variables: file (the
# README, from the repository's root), check (1: also say, on stderr, where
# each excerpt differs from its source).
#
# An excerpt is
#
#   <!-- excerpt FILE NAME -->
#   `NAME`, from [`FILE`](link to FILE):
#
#   ```c
#   the definition of NAME in FILE, its leading comment included
#   ```
#   <!-- end of excerpt -->
#
# and everything between the two comments is written here. The lookup is
# docs/weave.lua's find_definition, line for line, so that the README and
# the book show the same lines (the weave refuses a README whose excerpt
# differs from what it reads). A block ```excerpt with lines "FILE NAME"
# (the form before the splice) becomes one such excerpt per line.

# ---- reading C: docs/weave.lua's matching_brace, comment_start and
# find_definition, in awk. L[1..n] holds the source's lines.

# The line on which the brace opened at or after line `first` closes, or 0
# when the first of '{' and ';' is ';' (a declaration, not a body).
function matching_brace(first, n,    depth, opened, in_comment, i, line, k, c, two, j) {
    depth = 0; opened = 0; in_comment = 0
    for (i = first; i <= n; i++) {
        line = L[i]
        k = 1
        while (k <= length(line)) {
            c = substr(line, k, 1)
            two = substr(line, k, 2)
            if (in_comment) {
                if (two == "*/") { in_comment = 0; k++ }
            } else if (two == "/*") {
                in_comment = 1; k++
            } else if (two == "//") {
                break
            } else if (c == "\"" || c == "'") {
                j = k + 1
                while (j <= length(line) && substr(line, j, 1) != c) {
                    if (substr(line, j, 1) == "\\") j++
                    j++
                }
                k = j
            } else if (c == "{") {
                depth++; opened = 1
            } else if (c == "}") {
                depth--
                if (opened && depth == 0) return i
            } else if (c == ";" && !opened) {
                return 0
            }
            k++
        }
    }
    return 0
}

# The comment block ending just above line `start` (if any) begins here.
function comment_start(start,    i, j) {
    i = start - 1
    if (i >= 1 && L[i] ~ /\*\/[[:space:]]*$/) {
        while (i >= 1 && index(L[i], "/*") == 0) i--
        return i < 1 ? 1 : i
    }
    j = start
    while (j - 1 >= 1 && L[j - 1] ~ /^[[:space:]]*\/\//) j--
    return j
}

# Sets FIRST and LAST to the lines of NAME's definition in L[1..n]; 0 if none.
function find_definition(name, n,    i, line, j, last, c, before, s) {
    s = "[[:space:]]"
    for (i = 1; i <= n; i++) {
        line = L[i]
        # #define NAME ...
        if (line ~ ("^#" s "*define" s "+" name "(" s "|\\(|$)")) {
            last = i
            while (L[last] ~ /\\[[:space:]]*$/ && last < n) last++
            FIRST = comment_start(i); LAST = last; return 1
        }
        # enum { NAME = 4 };  a constant in a one-line enum
        if (line ~ ("^enum" s "*[{]([^}]*[^A-Za-z0-9_])?" name s "*=")) {
            FIRST = comment_start(i); LAST = i; return 1
        }
        # } name;  closing a typedef of a struct, union or enum
        if (line ~ ("^[}]" s "*" name s "*;")) {
            j = i
            while (j >= 1 && L[j] !~ /^typedef/) j--
            if (j >= 1) { FIRST = comment_start(j); LAST = i; return 1 }
        }
        # struct name { / enum name { / typedef struct name {
        if (line ~ ("^struct" s "+" name s "*[{]") || line ~ ("^enum" s "+" name s "*[{]") \
            || line ~ ("^union" s "+" name s "*[{]") || line ~ ("^typedef" s "+[A-Za-z]+" s "+" name s "*[{]")) {
            last = matching_brace(i, n)
            if (last) { FIRST = comment_start(i); LAST = last; return 1 }
        }
        # A function definition: its signature starts in column 0 and a body follows.
        if (line ~ /^[A-Za-z_]/ && line !~ /^typedef/ \
            && (line ~ ("^" name s "*\\(") || line ~ ("[^A-Za-z0-9_]" name s "*\\("))) {
            match(line, name s "*\\(")
            before = substr(line, 1, RSTART - 1)
            # not a call inside an initializer, not a macro's use
            if (before !~ /[=,(]/) {
                last = matching_brace(i, n)
                if (last) { FIRST = comment_start(i); LAST = last; return 1 }
            }
        }
        # enum { NAME = ... } or a constant: `static const float NAME = ...;`
        if (line ~ ("^" s "+" name s "*=") || line ~ ("^static" s "+const" s "+[A-Za-z0-9_ ]+" s name s "*=")) {
            FIRST = i; last = i
            while (index(L[last], ";") == 0 && L[last] !~ /,[[:space:]]*$/ \
                   && L[last] !~ /,[[:space:]]*\/[\/*]/ && last < n) last++
            c = FIRST - 1
            if (c >= 1 && L[c] ~ /\*\/[[:space:]]*$/) {
                while (c >= 1 && index(L[c], "/*") == 0) c--
                FIRST = c < 1 ? 1 : c
            }
            LAST = last; return 1
        }
    }
    return 0
}

# ---- the README

# How the README links a file of the repository: relative to its directory.
function link_to(path,    dir, up) {
    dir = file
    sub(/^\.\//, "", dir)
    if (dir !~ /\//) return path
    sub(/\/[^\/]*$/, "", dir)
    if (index(path, dir "/") == 1) return substr(path, length(dir) + 2)
    up = dir
    gsub(/[^\/]+/, "..", up)
    return up "/" path
}

# Fills G[1..GN] with the lines an excerpt of NAME from SRC holds after its
# opening comment (the closing comment last). Returns 0, having said why on
# stderr, when there is no such file or definition.
function excerpt(src, name, at,    n, line, i) {
    n = 0
    while ((getline line < (source_root src)) > 0) L[++n] = line
    close(source_root src)
    if (n == 0) {
        printf "%s:%d: excerpt: no file %s\n", file, at, src > "/dev/stderr"
        return 0
    }
    if (!find_definition(name, n)) {
        printf "%s:%d: excerpt: %s is not defined in %s any more\n", file, at, name, src > "/dev/stderr"
        return 0
    }
    GN = 0
    G[++GN] = "`" name "`, from [`" src "`](" link_to(src) "):"
    G[++GN] = ""
    G[++GN] = "```c"
    for (i = FIRST; i <= LAST; i++) G[++GN] = L[i]
    G[++GN] = "```"
    G[++GN] = "<!-- end of excerpt -->"
    return 1
}

function emit(src, name, at,    i) {
    print "<!-- excerpt " src " " name " -->"
    if (!excerpt(src, name, at)) { failed = 1; GN = 0; print END_LINE; return }
    for (i = 1; i <= GN; i++) print G[i]
}

function differs(line, name, src) {
    if (check) printf "%s:%d: %s (from %s): the excerpt differs from the source here; `make excerpts` writes it\n", \
        file, line, name, src > "/dev/stderr"
    stale = 1
}

BEGIN { END_LINE = "<!-- end of excerpt -->"; state = "text" }

state == "region" {
    k++
    if (!bad && (k > GN || $0 != G[k])) bad = NR
    if ($0 == END_LINE) {
        if (!bad && k != GN) bad = NR
        if (bad) differs(bad, name, src)
        state = "text"
    }
    next
}

state == "block" {
    if ($0 ~ /^```/) { state = "text"; next }
    if ($0 !~ /[^[:space:]]/) next
    if (split($0, w, " ") != 2) {
        printf "%s:%d: an excerpt line is `FILE NAME` (from the repository's root), not `%s`\n", file, NR, $0 > "/dev/stderr"
        failed = 1
        next
    }
    if (refs++) print ""
    emit(w[1], w[2], NR)
    if (check) printf "%s:%d: %s (from %s): an ```excerpt block, not filled in; `make excerpts` writes it\n", \
        file, NR, w[2], w[1] > "/dev/stderr"
    stale = 1
    next
}

/^<!-- excerpt [^ ]+ [A-Za-z_][A-Za-z0-9_]* -->$/ {
    src = $3; name = $4
    emit(src, name, NR)
    state = "region"; k = 0; bad = 0; start = NR
    next
}

/^```excerpt[[:space:]]*$/ { state = "block"; refs = 0; next }

{ print }

END {
    if (state == "region") {
        printf "%s:%d: the excerpt of %s has no `%s`\n", file, start, name, END_LINE > "/dev/stderr"
        failed = 1
    }
    if (failed) exit 2
    exit stale ? 1 : 0
}
