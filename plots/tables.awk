# tables.awk -- what the measured tables (plots/*.table) share: reading a
# CSV of doubling runs and reading a time or an error off it. Loaded before
# each table by `make plots`: awk -v data_dir=DIR -f plots/tables.awk -f T.

# Reads FILE's rows whose column KEY_COL equals KEY into run[1..n]: the CPU
# seconds (column CPU_COL) and the error (column ERR_COL). Columns count
# from the end when negative (labels may hold commas). Returns n.
function runs_read(file, key_col, key, cpu_col, err_col,    line, f, n, c, k) {
    n = 0
    while ((getline line < file) > 0) {
        if (line !~ /^[0-9a-z-]+,/ || line ~ /^[a-z_]+,[a-z_]+,/) continue
        c = split(line, f, ",")
        k = key_col < 0 ? f[c + 1 + key_col] : f[key_col]
        if (k != key) continue
        n++
        run_cpu[n] = (cpu_col < 0 ? f[c + 1 + cpu_col] : f[cpu_col]) + 0
        run_err[n] = (err_col < 0 ? f[c + 1 + err_col] : f[err_col]) + 0
        run_row[n] = line
    }
    close(file)
    return n
}

# The CPU time at which the runs first reach error TARGET, log-log between
# the run before and the run that does; -1 if none does.
function time_to(n, target,    k, f) {
    for (k = 1; k <= n; k++) {
        if (run_err[k] > target) continue
        if (k == 1 || run_err[k - 1] <= run_err[k] || run_cpu[k - 1] <= 0) return run_cpu[k]
        f = (log(target) - log(run_err[k - 1])) / (log(run_err[k]) - log(run_err[k - 1]))
        return exp(log(run_cpu[k - 1]) + f * (log(run_cpu[k]) - log(run_cpu[k - 1])))
    }
    return -1
}

# The error at CPU time T, log-log between the runs around it (the runs
# in the order they were made, which is the order of their cost).
function error_at(n, t,    k, f) {
    for (k = 2; k <= n; k++) {
        if (run_cpu[k] < t) continue
        if (run_cpu[k - 1] >= t || run_cpu[k - 1] <= 0 || run_err[k - 1] <= 0 || run_err[k] <= 0) return run_err[k]
        f = (log(t) - log(run_cpu[k - 1])) / (log(run_cpu[k]) - log(run_cpu[k - 1]))
        return exp(log(run_err[k - 1]) + f * (log(run_err[k]) - log(run_err[k - 1])))
    }
    return run_err[n]
}

# The largest CPU time of the runs.
function runs_longest(n,    k, t) {
    t = 0
    for (k = 1; k <= n; k++) if (run_cpu[k] > t) t = run_cpu[k]
    return t
}

# An error as the tables print it: three decimals down to 0.01, then 1.2e-03.
function error_text(x) { return x >= 0.01 ? sprintf("%.3f", x) : sprintf("%.1e", x) }
# A time: "0.25 s", or "–" for never.
function time_text(t) { return t < 0 ? "–" : sprintf("%.2f s", t) }

# A whole number as superscript digits (10⁷), which every Markdown shows.
function superscript(n,    s, d, k) {
    split("⁰ ¹ ² ³ ⁴ ⁵ ⁶ ⁷ ⁸ ⁹", d, " ")
    s = ""
    n = sprintf("%d", n)
    for (k = 1; k <= length(n); k++) s = s (substr(n, k, 1) == "-" ? "⁻" : d[substr(n, k, 1) + 1])
    return s
}
# A signed number with the minus sign typography uses (−0.50).
function signed(x, format) { return x < 0 ? "−" sprintf(format, -x) : sprintf(format, x) }

# The number a program's counters file (FILE.counters.json, one key a line)
# holds under KEY; -1 if it has none.
function json_count(json, key,    line, v) {
    v = -1
    while ((getline line < json) > 0)
        if (line ~ "\"" key "\":") { v = line; sub(/^[^:]*:[ ]*/, "", v); sub(/,$/, "", v) }
    close(json)
    return v + 0
}
