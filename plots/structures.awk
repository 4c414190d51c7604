# structures.awk -- reading chapters 04-06's reports (build/data/chNN_*.log,
# from mk/plots.mk's structure-data), loaded before their tables:
# awk -v data_dir=DIR -f plots/tables.awk -f plots/structures.awk -f T.

# The number in FILE's first line holding KEY that the regular expression
# PAT (a number, then text) matches; "" if none.
function report(file, key, pat,    line, v) {
    v = ""
    while ((getline line < file) > 0)
        if (index(line, key) > 0 && match(line, pat)) {
            v = substr(line, RSTART, RLENGTH)
            sub(/^[^0-9]*/, "", v)
            v = v + 0
            break
        }
    close(file)
    return v
}
# 1234567 -> "1 234 567", as the chapters write large counts.
function spaced(n,    s, out) {
    s = sprintf("%d", n)
    out = ""
    while (length(s) > 3) { out = " " substr(s, length(s) - 2) out; s = substr(s, 1, length(s) - 3) }
    return s out
}
