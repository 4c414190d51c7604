#!/usr/bin/env python3
"""exercise.py -- the chapters as assignments: hand out, take back, grade.

A function that carries a lecture's idea is marked in the source, one
comment line at each end of its body:

    bool sphere_roots(...)
    {
        /* exercise: sphere_roots */
        ...the reference body...
        /* end of exercise sphere_roots */
    }

(a struct whose zero is not "nothing" names its stub's value in the first
line: "/* exercise: NAME; a stub returns EXPR */"), and the chapter's
README says what it asks, where its text explains it:

    > **Exercise `sphere_roots`** (GAMES101 assignment 5): ...
    >
    > ```
    > the slide's formula or pseudo-code
    > ```

The source holds the only copy of the reference body; everything else is
made from it: the stub (a neutral return value, the README's formula as a
comment, a call that says the exercise is still a stub), the grading table
(from the tests that name the exercise with exercise_checks()), the
reference picture beside the learner's.

Commands (the Makefile's `make exercise`, `solution`, `grade`, `chNN` and
`check-exercises` call them):
    list      [--ch NN]                 the exercises, their files and sections
    handout   --ch NN [--ex NAME]       stubs in place of reference bodies
    solution  --ch NN [--ex NAME]       reference bodies back, the learner's kept
    status                              each exercise: reference, stub or yours
    handed-out                          exit 0 if any exercise is not the reference
    reference-tree DIR                  a copy of the tree with every reference body
    grade     [--ch NN] --build DIR     run the suites, print one table
    picture   NN --build DIR -- ARGS    the reference picture and the difference
    check     [--ch NN] [--ex NAME] [--plant]   every exercise: stub fails, solution restores

No learner's work is ever lost: handing out rewrites only bodies that are
the reference; taking back saves any other body under .exercises/yours/
before the reference goes back, and handing out again brings it back.
"""

import argparse
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
START = re.compile(r'^(\s*)/\* exercise: (\w+)(?:; a stub returns (.*?))? \*/\s*$')
END = re.compile(r'^\s*/\* end of exercise (\w+) \*/\s*$')
README_BLOCK = re.compile(r'^> \*\*Exercise `(\w+)`\*\*(.*)$')
HEADING = re.compile(r'^(#{1,6})\s+(.*?)\s*#*\s*$')
STUB_CALL = 'exercise_todo('
INCLUDE_LINE = '#include "exercise.h" /* added by make exercise; make solution takes it out */\n'
STATE_DIR = '.exercises'


class Refusal(Exception):
    """A reason to stop without writing anything, said to the learner."""


# ---- where the exercises are ----------------------------------------------

def chapter_dirs(root):
    base = os.path.join(root, 'chapters')
    return sorted(d for d in os.listdir(base) if re.match(r'^\d\d-', d))


def chapter_dir(root, number):
    for d in chapter_dirs(root):
        if d.startswith('%02d-' % int(number)):
            return d
    raise Refusal('no chapter %s under chapters/' % number)


def github_anchor(title):
    """The anchor GitHub gives a heading: lower case, punctuation dropped,
    spaces to hyphens."""
    title = re.sub(r'`|\*', '', title).strip().lower()
    title = re.sub(r'[^\w\- ]', '', title)
    return title.replace(' ', '-')


def readme_exercises(root, chapter):
    """The exercise blocks of one chapter's README, in reading order."""
    path = os.path.join('chapters', chapter, 'README.md')
    try:
        lines = open(os.path.join(root, path), encoding='utf-8').read().split('\n')
    except OSError:
        return []
    found, section, fenced = [], None, False
    for i, line in enumerate(lines):
        if line.startswith('```'):
            fenced = not fenced
        heading = HEADING.match(line)
        if heading and not fenced:
            section = heading.group(2)
        block = README_BLOCK.match(line)
        if not block:
            continue
        quote = []
        for later in lines[i:]:
            if not later.startswith('>'):
                break
            quote.append(later[2:] if later.startswith('> ') else later[1:])
        hint, in_code = [], False
        for q in quote:
            if q.startswith('```'):
                in_code = not in_code
            elif in_code:
                hint.append(q)
        found.append({
            'name': block.group(1), 'chapter': chapter, 'readme': path, 'line': i + 1,
            'section': section or chapter, 'where': '%s#%s' % (path, github_anchor(section or '')),
            'hint': hint, 'assignment': re.search(r'assignment (\d+)', line),
        })
    return found


def all_exercises(root):
    exercises = []
    for chapter in chapter_dirs(root):
        exercises.extend(readme_exercises(root, chapter))
    return exercises


def source_files(root):
    for top in ('common', 'chapters'):
        for dirpath, _, files in os.walk(os.path.join(root, top)):
            for f in sorted(files):
                if f.endswith(('.c', '.h')):
                    yield os.path.relpath(os.path.join(dirpath, f), root)


def find_markers(root):
    """name -> (file, start index, end index) of every marked body; refuses
    a start without its end (a marker edited away)."""
    marks = {}
    for rel in source_files(root):
        lines = read_lines(root, rel)
        open_name, open_at = None, None
        for i, line in enumerate(lines):
            s, e = START.match(line), END.match(line)
            if s:
                if open_name:
                    raise Refusal('%s:%d: exercise %s starts before %s ends' % (rel, i + 1, s.group(2), open_name))
                open_name, open_at = s.group(2), i
            elif e:
                if e.group(1) != open_name:
                    raise Refusal('%s:%d: end of exercise %s without its start' % (rel, i + 1, e.group(1)))
                if open_name in marks:
                    raise Refusal('%s:%d: exercise %s is marked twice' % (rel, i + 1, open_name))
                marks[open_name] = (rel, open_at, i)
                open_name = None
        if open_name:
            raise Refusal('%s:%d: exercise %s has no "/* end of exercise %s */" line'
                          % (rel, open_at + 1, open_name, open_name))
    return marks


def read_lines(root, rel):
    with open(os.path.join(root, rel), encoding='utf-8') as f:
        return f.readlines()


def write_atomically(root, rel, lines):
    """Whole or not at all: a temporary file beside it, then a rename."""
    path = os.path.join(root, rel)
    tmp = path + '.exercise-tmp'
    with open(tmp, 'w', encoding='utf-8') as f:
        f.writelines(lines)
    shutil.copymode(path, tmp)
    os.replace(tmp, path)


# ---- the function around a marked body ------------------------------------

def signature(lines, start, rel):
    """(return type, parameter names, names of locals declared before the
    start marker) of the function whose body holds the marker at `start`."""
    brace = start - 1
    while brace >= 0 and '{' not in lines[brace]:
        brace -= 1
    while brace >= 0 and lines[brace].strip() != '{' and not lines[brace].rstrip().endswith(')') \
            and not re.search(r'\)\s*\{\s*$', lines[brace]):
        brace -= 1
    # The body opens at the first line that is only "{" or ends ") {".
    open_at = brace
    top = open_at
    while top > 0 and lines[top - 1].strip() and not lines[top - 1].rstrip().endswith(('*/', ';', '}')):
        top -= 1
    head = ' '.join(l.strip() for l in lines[top:open_at + 1])
    head = head.split('{')[0]
    m = re.match(r'^(?P<ret>.*?)\b(?P<name>\w+)\s*\((?P<params>.*)\)\s*$', head)
    if not m:
        raise Refusal('%s:%d: cannot read the function around this exercise' % (rel, start + 1))
    ret = ' '.join(w for w in m.group('ret').split() if w not in ('static', 'inline', 'extern'))
    params = []
    for p in split_top(m.group('params')):
        p = re.sub(r'\[[^\]]*\]', '', p).strip()
        if p and p != 'void':
            params.append(re.findall(r'\w+', p)[-1])
    local_names = []
    for l in lines[open_at + 1:start]:
        decl = re.match(r'^\s*(?:const\s+)?\w+[\s\*]+(\w+.*);\s*(?://.*|/\*.*)?$', l)
        if decl and not re.match(r'^\s*(return|if|for|while)\b', l):
            for part in split_top(decl.group(1)):
                name = re.match(r'\s*\**\s*(\w+)', part)
                if name:
                    local_names.append(name.group(1))
    return ret, m.group('name'), params, local_names


def split_top(text):
    """Split on commas outside parentheses and braces."""
    parts, depth, cur = [], 0, ''
    for ch in text:
        if ch in '([{':
            depth += 1
        elif ch in ')]}':
            depth -= 1
        if ch == ',' and depth == 0:
            parts.append(cur)
            cur = ''
        else:
            cur += ch
    if cur.strip():
        parts.append(cur)
    return parts


def neutral_return(ret):
    """What a stub returns: nothing found, nothing added, no light."""
    if ret == 'void':
        return None
    if ret.endswith('*'):
        return 'NULL'
    if ret in ('bool', '_Bool'):
        return 'false'
    if ret in ('int', 'unsigned', 'long', 'size_t', 'float', 'double', 'int32_t', 'int64_t',
               'uint32_t', 'uint64_t', 'unsigned int', 'long long'):
        return '0'
    return '(%s){0}' % ret


def static_helpers(lines, body):
    """Static functions and constants of the file that the reference body
    uses: with the body gone they would be unused (a warning), so the stub
    names them, and in doing so tells the learner what there is to use."""
    defined = set()
    for l in lines:
        m = re.match(r'^static\s+(?:inline\s+)?(?:const\s+)?[\w\s\*]+?\b(\w+)\s*(?:\(|=|\[)', l)
        if m:
            defined.add(m.group(1))
    text = ''.join(body)
    return [name for name in sorted(defined) if re.search(r'\b%s\b' % name, text)]


def make_stub(ex, lines, start, end, rel, reference):
    marker = START.match(lines[start])
    indent = marker.group(1)
    ret, function, params, local_names = signature(lines, start, rel)
    out = ['%s/* Write %s() here: "%s" in %s explains it.\n' % (indent, function, ex['section'], ex['readme'])]
    for h in ex['hint']:
        out.append(('%s *     %s' % (indent, h.replace('*/', '* /'))).rstrip() + '\n')
    out.append('%s */\n' % indent)
    out.append('%sexercise_todo("%s", "%s");\n' % (indent, ex['name'], ex['where']))
    helpers = [h for h in static_helpers(lines[:start] + lines[end + 1:], reference) if h != function]
    if helpers:
        out.append('%s/* what this file has for it: %s (keep a (void) line below for each you do not\n'
                   % (indent, ', '.join(helpers)))
        out.append('%s * use: a static function nothing calls is a warning) */\n' % indent)
    for name in params + local_names + helpers:
        out.append('%s(void)%s;\n' % (indent, name))
    value = marker.group(3) or neutral_return(ret)
    if value is not None:
        out.append('%sreturn %s;\n' % (indent, value))
    return out


# ---- the three states of a body -------------------------------------------

def body_of(lines, start, end):
    return lines[start + 1:end]


def is_stub(body):
    return any(STUB_CALL in l for l in body)


def state_path(root, kind, rel, name, n=0):
    suffix = '' if n == 0 else '.%d' % n
    return os.path.join(root, STATE_DIR, kind, rel, name + suffix + '.c')


def git_head_lines(root, rel):
    try:
        out = subprocess.run(['git', 'show', 'HEAD:' + rel], cwd=root, capture_output=True, check=True)
        return out.stdout.decode('utf-8').splitlines(keepends=True)
    except (OSError, subprocess.CalledProcessError):
        return None


def reference_body(root, name, rel, lines, start, end):
    """The reference: the copy saved when it was first handed out, else the
    committed body (git), else the body as it is, if it is not a stub."""
    saved = state_path(root, 'reference', rel, name)
    if os.path.exists(saved):
        return open(saved, encoding='utf-8').readlines()
    head = git_head_lines(root, rel)
    if head is not None:
        try:
            marks = marker_lines(head, name)
            candidate = body_of(head, *marks)
            if not is_stub(candidate):
                return candidate
        except Refusal:
            pass
    current = body_of(lines, start, end)
    if not is_stub(current):
        return current
    raise Refusal('%s: the reference body of %s is nowhere (not saved in %s/, not in git HEAD): '
                  'git checkout %s brings the whole file back' % (rel, name, STATE_DIR, rel))


def marker_lines(lines, name):
    start = end = None
    for i, l in enumerate(lines):
        s, e = START.match(l), END.match(l)
        if s and s.group(2) == name:
            start = i
        if e and e.group(1) == name and start is not None:
            end = i
            break
    if start is None or end is None:
        raise Refusal('exercise %s is not marked' % name)
    return start, end


def save(path, body):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'w', encoding='utf-8') as f:
        f.writelines(body)


def with_include(lines):
    if INCLUDE_LINE in lines:
        return lines
    for i, l in enumerate(lines):
        if l.startswith('#include'):
            return lines[:i + 1] + [INCLUDE_LINE] + lines[i + 1:]
    return [INCLUDE_LINE] + lines


def without_include_if_unused(lines):
    if any(STUB_CALL in l for l in lines if l != INCLUDE_LINE and 'exercise_todo(const' not in l):
        return lines
    return [l for l in lines if l != INCLUDE_LINE]


def selected(root, chapter, only):
    exercises = readme_exercises(root, chapter) if chapter else all_exercises(root)
    if only:
        exercises = [e for e in exercises if e['name'] == only]
        if not exercises:
            raise Refusal('no exercise %s in %s' % (only, chapter or 'any chapter'))
    if not exercises:
        raise Refusal('chapter %s has no exercises' % chapter)
    marks = find_markers(root)
    for e in exercises:
        if e['name'] not in marks:
            raise Refusal('%s:%d: exercise %s is in the README but no source marks it'
                          % (e['readme'], e['line'], e['name']))
    return exercises, marks


def exact_stub(ex, lines, start, end, rel, reference):
    """Is the body the stub handing out writes, to the letter? Anything
    else that is not the reference is the learner's (a half-written body
    that still calls exercise_todo() too), and is never thrown away."""
    return body_of(lines, start, end) == make_stub(ex, lines, start, end, rel, reference)


def state_of(root, ex, marks):
    rel, start, end = marks[ex['name']]
    lines = read_lines(root, rel)
    body = body_of(lines, start, end)
    ref = reference_body(root, ex['name'], rel, lines, start, end)
    if exact_stub(ex, lines, start, end, rel, ref):
        return 'stub'
    return 'reference' if body == ref else 'yours'


# ---- handing out and taking back ----------------------------------------

def keep_yours(root, rel, name, body):
    """Save a learner's body as NAME.c, the newest; an older, different one
    moves to NAME.1.c, NAME.2.c, ... first. Returns where it is."""
    newest = state_path(root, 'yours', rel, name)
    if os.path.exists(newest):
        if open(newest, encoding='utf-8').readlines() == body:
            return newest
        n = 1
        while os.path.exists(state_path(root, 'yours', rel, name, n)):
            n += 1
        os.replace(newest, state_path(root, 'yours', rel, name, n))
    save(newest, body)
    return newest


def each_marked(root, chapter, only):
    """Each exercise chosen, with its file, the file's lines, where its body
    is, the body and the reference body."""
    exercises, marks = selected(root, chapter, only)
    for ex in exercises:
        rel = marks[ex['name']][0]
        lines = read_lines(root, rel)
        start, end = marker_lines(lines, ex['name'])
        ref = reference_body(root, ex['name'], rel, lines, start, end)
        yield ex, rel, lines, start, end, body_of(lines, start, end), ref


def handout(root, chapter, only):
    for ex, rel, lines, start, end, body, ref in each_marked(root, chapter, only):
        name = ex['name']
        if not os.path.exists(state_path(root, 'reference', rel, name)):
            save(state_path(root, 'reference', rel, name), ref)
        yours = state_path(root, 'yours', rel, name)
        if exact_stub(ex, lines, start, end, rel, ref):
            print('%-22s %s: handed out already (a stub)' % (name, rel))
            continue
        if body != ref:
            print('%-22s %s: your version is there, kept' % (name, rel))
            continue
        if os.path.exists(yours):
            new = open(yours, encoding='utf-8').readlines()
            print('%-22s %s: your version is back (the one make solution kept in %s)'
                  % (name, rel, os.path.relpath(yours, root)))
        else:
            new = make_stub(ex, lines, start, end, rel, ref)
            print('%-22s %s: handed out; "%s" explains it' % (name, rel, ex['section']))
        lines = lines[:start + 1] + new + lines[end:]
        write_atomically(root, rel, with_include(lines) if is_stub(new) else lines)


def solution(root, chapter, only):
    for ex, rel, lines, start, end, body, ref in each_marked(root, chapter, only):
        name = ex['name']
        if body == ref:
            print('%-22s %s: the reference already' % (name, rel))
            forget_reference(root, rel, name)
            continue
        if exact_stub(ex, lines, start, end, rel, ref):
            print('%-22s %s: the reference is back' % (name, rel))
        else:
            kept = keep_yours(root, rel, name, body)
            print('%-22s %s: the reference is back; yours is kept in %s (make exercise brings it back)'
                  % (name, rel, os.path.relpath(kept, root)))
        lines = lines[:start + 1] + ref + lines[end:]
        write_atomically(root, rel, without_include_if_unused(lines))
        forget_reference(root, rel, name)


def forget_reference(root, rel, name):
    """The saved reference lives only while the exercise is out: once the
    reference is back in the source, the source (and git) hold it, and a
    later change to it upstream must not meet an old copy."""
    saved = state_path(root, 'reference', rel, name)
    if os.path.exists(saved):
        os.remove(saved)


def status(root):
    marks = find_markers(root)
    for ex in all_exercises(root):
        if ex['name'] in marks:
            print('%-22s %-10s %s' % (ex['name'], state_of(root, ex, marks), marks[ex['name']][0]))


def any_handed_out(root):
    marks = find_markers(root)
    return any(e['name'] in marks and state_of(root, e, marks) != 'reference' for e in all_exercises(root))


def list_exercises(root, chapter):
    marks = find_markers(root)
    exercises = readme_exercises(root, chapter) if chapter else all_exercises(root)
    for ex in exercises:
        rel = marks.get(ex['name'], ('(not marked in any source)',))[0]
        a = ex['assignment']
        print('%s  %-22s %-44s %s%s' % (ex['chapter'][:2], ex['name'], rel, ex['where'],
                                          '  (GAMES101 assignment %s)' % a.group(1) if a else ''))


# ---- grading ----------------------------------------------------------------

def run_suite(binary, test_filter=None, timeout=600):
    """Run a cmocka suite with EXERCISE_GRADE set; per test: the exercises
    it names, whether it passed, its failure lines."""
    env = dict(os.environ, EXERCISE_GRADE='1')
    if test_filter:
        env['TEST_FILTER'] = test_filter
    try:
        out = subprocess.run([binary], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             timeout=timeout).stdout.decode('utf-8', 'replace')
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b'').decode('utf-8', 'replace') + '\n[  FAILED  ] (timed out after %d s)\n' % timeout
    tests, current = {}, None
    for line in out.replace('[  ERROR   ] --- [   LINE   ]', '[   LINE   ]').split('\n'):
        run = re.match(r'^\[ RUN      \] (\S+)', line)
        done = re.match(r'^\[ +(OK|FAILED|SKIPPED) +\] (\S+)', line)
        if run:
            current = {'exercises': [], 'result': None, 'messages': []}
            tests[run.group(1)] = current
        elif done and current is not None and current['result'] is None:
            current['result'] = done.group(1)
            current = None
        elif current is not None:
            ex = re.match(r'^exercise: (\w+)$', line)
            if ex:
                current['exercises'].append(ex.group(1))
            elif line.strip() and not line.startswith('exercise ') and not line.startswith('['):
                current['messages'].append(line.strip())
            else:
                said = re.match(r'^\[  ERROR   \] --- (.*)$', line)
                at = re.match(r'^\[   LINE   \] --- (\S+:\d+): error: (.*)$', line)
                if said:
                    current['messages'].append(plain_failure(said.group(1)))
                elif at:
                    current['messages'].append('at %s' % at.group(1))
    for t in tests.values():
        if t['result'] is None:
            t['result'] = 'FAILED'
            t['messages'].append('the suite stopped in this test (a crash or a time-out)')
    return tests, out


def plain_failure(text):
    """cmocka's words for a failed assertion, as a learner reads them."""
    m = re.match(r'^(\S+) != (\S+)$', text)
    if m:
        got, expected = (str(int(v, 16)) if re.match(r'^0x[0-9a-f]+$', v) else v for v in m.groups())
        return 'got %s where %s was expected' % (got, expected)
    if re.search(r'[a-z_]\w*\(', text) or '==' in text or '<' in text or '>' in text:
        return 'expected true: %s' % text
    return text


def build_suite(root, build, number):
    target = os.path.join(build, 'tests', 'test_ch%02d' % int(number))
    r = subprocess.run(['make', '--no-print-directory', '-s', target], cwd=root,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    return target, r.returncode == 0, r.stdout.decode('utf-8', 'replace')


def grade(root, chapters, build):
    marks = find_markers(root)
    failed_any, summary = False, {True: 0, False: 0}
    for chapter in chapters:
        exercises = [e for e in readme_exercises(root, chapter) if e['name'] in marks]
        if not exercises:
            continue
        number = chapter[:2]
        binary, built, log = build_suite(root, build, number)
        print('chapter %s: %d exercises, graded by tests/test_ch%s.c' % (chapter, len(exercises), number))
        if not built:
            print(log.rstrip())
            print('  does not build: fix the errors above first')
            failed_any = True
            continue
        if 'warning:' in log:
            print(log.rstrip())
            print('  (the compiler warns: above)')
        tests, _ = run_suite(os.path.join(root, binary))
        print('  %-22s %-9s %-7s %s' % ('exercise', 'state', 'tests', 'result'))
        for ex in exercises:
            mine = [(n, t) for n, t in tests.items() if ex['name'] in t['exercises']]
            passed = sum(1 for _, t in mine if t['result'] == 'OK')
            failed = [(n, t) for n, t in mine if t['result'] == 'FAILED']
            verdict = 'no test names it' if not mine else 'pass' if not failed else 'FAIL'
            print('  %-22s %-9s %d/%-5d %s' % (ex['name'], state_of(root, ex, marks), passed, len(mine), verdict))
            for n, t in failed:
                print('      %s' % n)
                for m in t['messages'][-4:]:
                    print('          %s' % m)
            if failed:
                print('      read: %s ("%s")' % (ex['where'], ex['section']))
            failed_any = failed_any or bool(failed) or not mine
            summary[verdict == 'pass'] += 1
    print('%d exercises pass, %d do not' % (summary[True], summary[False]))
    return 1 if failed_any else 0


# ---- the reference picture beside the learner's -------------------------

def reference_tree(root, dest):
    """A copy of the tree with every marked body the reference. Files are
    written only where their content changes, so the reference build
    recompiles only what changed since the last picture."""
    marks = find_markers(root)
    wanted = {}
    for ex in all_exercises(root):
        if ex['name'] not in marks:
            continue
        rel = marks[ex['name']][0]
        lines = wanted.get(rel) or read_lines(root, rel)
        start, end = marker_lines(lines, ex['name'])
        ref = reference_body(root, ex['name'], rel, lines, start, end)
        wanted[rel] = without_include_if_unused(lines[:start + 1] + ref + lines[end:])
    for dirpath, dirnames, files in os.walk(root):
        rel_dir = os.path.relpath(dirpath, root)
        if rel_dir == '.':
            dirnames[:] = [d for d in dirnames if d not in ('build', '.git', STATE_DIR)]
        for f in files:
            rel = os.path.normpath(os.path.join(rel_dir, f))
            target = os.path.join(dest, rel)
            os.makedirs(os.path.dirname(target), exist_ok=True)
            if rel in wanted:
                content = ''.join(wanted[rel]).encode('utf-8')
                if not os.path.exists(target) or open(target, 'rb').read() != content:
                    with open(target, 'wb') as out:
                        out.write(content)
            elif not os.path.exists(target) or os.path.getmtime(target) != os.path.getmtime(os.path.join(root, rel)):
                shutil.copy2(os.path.join(root, rel), target)


def picture(root, number, build, args):
    if not any_handed_out(root):
        return 0
    chapter = chapter_dir(root, number)
    out_dir = os.path.join(build, 'out')
    yours = os.path.join(out_dir, 'ch%s.exr' % number)
    for i, a in enumerate(args[:-1]):
        if a == '--out':
            yours = args[i + 1]
    if not os.path.exists(os.path.join(root, yours)):
        return 0
    ref_build = os.path.join(root, build, 'reference')
    src = os.path.join(ref_build, 'src')
    os.makedirs(src, exist_ok=True)
    reference_tree(root, src)
    program = os.path.join(ref_build, 'bin', chapter)
    r = subprocess.run(['make', '--no-print-directory', '-s', 'BUILD=' + ref_build, program, '-j2'], cwd=src)
    if r.returncode != 0:
        print('the reference program did not build (above); no comparison', file=sys.stderr)
        return 1
    flags = [a for i, a in enumerate(args) if a != '--out' and (i == 0 or args[i - 1] != '--out')]
    seed = 1
    for i, a in enumerate(flags[:-1]):
        if a == '--seed':
            seed = int(flags[i + 1])
    # The reference twice: with the learner's seed, and with the next one.
    # How far apart those two are is the noise: a correct exercise that
    # draws its random numbers in another order differs by about as much.
    references = []
    for k, s_k in enumerate((seed, seed + 1)):
        reference = os.path.join(out_dir, 'ch%s.reference%s.exr' % (number, '' if k == 0 else '-seed%d' % s_k))
        seeded = [a for i, a in enumerate(flags) if a != '--seed' and (i == 0 or flags[i - 1] != '--seed')]
        run = [program, '--quiet'] + seeded + ['--seed', str(s_k), '--out', reference]
        key = hashlib.sha256(open(program, 'rb').read() + '\0'.join(run).encode()).hexdigest()
        key_file = os.path.join(root, reference + '.key')
        if not (os.path.exists(os.path.join(root, reference)) and os.path.exists(key_file)
                and open(key_file).read() == key):
            print('rendering the reference implementation\'s picture with the same flags%s...'
                  % ('' if k == 0 else ', seed %d' % s_k), file=sys.stderr)
            r = subprocess.run(run, cwd=root)
            if r.returncode != 0:
                return r.returncode
            with open(key_file, 'w') as f:
                f.write(key)
        references.append(reference)
    difference = os.path.join(out_dir, 'ch%s.difference.exr' % number)
    compare = os.path.join(root, build, 'bin', 'image_compare')
    r = subprocess.run(['make', '--no-print-directory', '-s', os.path.join(build, 'bin', 'image_compare')], cwd=root)
    if r.returncode != 0:
        return r.returncode
    return subprocess.run([compare, yours, references[0], difference, references[1]], cwd=root).returncode


# ---- the check of every exercise ------------------------------------------

def copy_tracked(root, dest):
    """The files git tracks, and those it would track (new, not ignored),
    as they are in the working tree; not the learner's .exercises/."""
    files = subprocess.run(['git', 'ls-files', '-z', '--cached', '--others', '--exclude-standard'], cwd=root,
                           capture_output=True, check=True).stdout
    for rel in files.decode().split('\0'):
        if not rel or rel.startswith(STATE_DIR + '/') or not os.path.exists(os.path.join(root, rel)):
            continue
        target = os.path.join(dest, rel)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copy2(os.path.join(root, rel), target)
    subprocess.run(['git', 'init', '-q'], cwd=dest, check=True)
    subprocess.run(['git', 'add', '-A'], cwd=dest, check=True)
    subprocess.run(['git', '-c', 'user.name=check', '-c', 'user.email=check@localhost', 'commit', '-q', '-m',
                    'the tree under check'], cwd=dest, check=True)


def plant(tree):
    """An exercise no test can catch: a function of chapter 01 that the test
    naming it never calls. The check must refuse it."""
    readme = os.path.join(tree, 'chapters', '01-ray-casting', 'README.md')
    with open(readme, 'a', encoding='utf-8') as f:
        f.write('\n## Planted\n\n> **Exercise `planted_untested`**: a body no test reaches.\n')
    rel = os.path.join('chapters', '01-ray-casting', 'scene.c')
    lines = read_lines(tree, rel)
    i = next(k for k, l in enumerate(lines) if l.startswith('const char *shape_kind_name('))
    assert lines[i + 1].strip() == '{'
    close = next(k for k in range(i + 2, len(lines)) if lines[k].startswith('}'))
    lines = lines[:i + 2] + ['    /* exercise: planted_untested */\n'] + lines[i + 2:close] + \
        ['    /* end of exercise planted_untested */\n'] + lines[close:]
    write_atomically(tree, rel, lines)
    test = os.path.join('tests', 'test_ch01.c')
    lines = read_lines(tree, test)
    i = next(k for k, l in enumerate(lines) if l.startswith('static void test_plane_hit_and_parallel_miss('))
    lines.insert(i + 2, '    exercise_checks("planted_untested");\n')
    write_atomically(tree, test, lines)
    subprocess.run(['git', 'commit', '-q', '-a', '-m', 'planted'], cwd=tree, check=True)


def check(root, chapter, only, planted, keep):
    tree = tempfile.mkdtemp(prefix='exercise-check-')
    errors, started = [], os.times()
    try:
        copy_tracked(root, tree)
        if planted:
            plant(tree)
            chapter, only = '01-ray-casting', 'planted_untested'
        build = 'build'
        werror = ['CFLAGS=-O2 -g -Werror']
        make = ['make', '--no-print-directory', '-s', '-j2'] + werror
        r = subprocess.run(make + ['all'], cwd=tree, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        if r.returncode != 0:
            print(r.stdout.decode('utf-8', 'replace'))
            raise Refusal('the tree under check does not build with -Werror')
        chapters = [chapter] if chapter else chapter_dirs(tree)
        for ch in chapters:
            exercises = readme_exercises(tree, ch)
            if only:
                exercises = [e for e in exercises if e['name'] == only]
            if not exercises:
                continue
            number = ch[:2]
            suite = os.path.join(tree, build, 'tests', 'test_ch%s' % number)
            # The last exercise's solution put its files back, not the
            # programs built from its stub: build them again first.
            subprocess.run(make + ['all'], cwd=tree, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            names, _ = run_suite(suite)
            for ex in exercises:
                errors += check_one(tree, ch, ex, names, make, build)
        if errors:
            print('\n'.join('check-exercises: ' + e for e in errors))
    except Refusal as e:
        errors.append(str(e))
        print('check-exercises: %s' % e)
    finally:
        if not keep:
            shutil.rmtree(tree, ignore_errors=True)
    t = os.times()
    cpu = (t.children_user + t.children_system) - (started.children_user + started.children_system)
    print('check-exercises: %d errors; %.0f s CPU in the builds, suites and programs' % (len(errors), cpu))
    if planted:
        ok = any('passes every test' in e for e in errors)
        print('check-exercises: the planted exercise was %s' % ('refused, as it must be' if ok else 'NOT refused'))
        return 0 if ok else 1
    return 1 if errors else 0


def check_one(tree, chapter, ex, names, make, build):
    name, errors = ex['name'], []
    tests = [n for n, t in names.items() if name in t['exercises']]
    broken = [n for n in tests if names[n]['result'] != 'OK']
    if not tests:
        return ['%s: no test names it (exercise_checks("%s") in tests/test_ch%s.c)' % (name, name, chapter[:2])]
    if broken:
        return ['%s: the reference fails its own tests: %s' % (name, ' '.join(broken))]
    marks = find_markers(tree)
    rel = marks[name][0]
    before = {r: open(os.path.join(tree, r), 'rb').read() for r in set(m[0] for m in marks.values())}
    lines = read_lines(tree, rel)
    reference = ''.join(body_of(lines, *marker_lines(lines, name)))
    handout(tree, chapter, name)
    handed = open(os.path.join(tree, rel), encoding='utf-8').read()
    if reference.strip() and reference in handed:
        errors.append('%s: the handed-out %s still holds the reference body' % (name, rel))
    r = subprocess.run(make + ['all'], cwd=tree, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        errors.append('%s: the handed-out tree does not build without warnings:\n%s'
                      % (name, r.stdout.decode('utf-8', 'replace')[-3000:]))
    else:
        suite = os.path.join(tree, build, 'tests', 'test_ch%s' % chapter[:2])
        caught = []
        for t in tests:
            result, _ = run_suite(suite, test_filter=t, timeout=300)
            if result.get(t, {}).get('result') == 'FAILED':
                caught.append(t)
        if not caught:
            errors.append('%s: the stub passes every test that names it (%s): no test can tell a wrong body'
                          % (name, ' '.join(tests)))
        program = os.path.join(tree, build, 'bin', chapter)
        errors += program_survives(tree, program, name)
        print('%-22s stub fails %d of %d tests: %s' % (name, len(caught), len(tests), ' '.join(caught) or '-'))
    solution(tree, chapter, name)
    for r_, content in before.items():
        if open(os.path.join(tree, r_), 'rb').read() != content:
            errors.append('%s: make solution did not give back %s as it was' % (name, r_))
    return errors


def program_survives(tree, program, name):
    """A stub never crashes a program: a small render runs to its end and
    says which exercise is still a stub."""
    out = os.path.join(tree, 'build', 'out', 'stub-%s.exr' % name)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    args = [program, '--width', '32', '--height', '24', '--spp', '1', '--threads', '2', '--out', out]
    if '07-' in program or '08-' in program:
        args = [program, '--quick', '--out', out] if '08-' in program else args
    try:
        r = subprocess.run(args, cwd=tree, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=300)
    except subprocess.TimeoutExpired:
        return ['%s: %s with the stub ran past 300 s' % (name, os.path.basename(program))]
    err = r.stderr.decode('utf-8', 'replace')
    # Exit 1 is a program's verdict (chapter 07's: "some values disagree"),
    # fine when the stub said it is one; a signal or any other status is not.
    said = 'exercise %s is still a stub' % name in err
    if r.returncode != 0 and not (r.returncode == 1 and said):
        return ['%s: %s with the stub exited %d:\n%s' % (name, os.path.basename(program), r.returncode, err[-2000:])]
    if not os.path.exists(out) and said:
        return ['%s: %s with the stub wrote no picture:\n%s' % (name, os.path.basename(program), err[-2000:])]
    return []


# ---- the command line -------------------------------------------------------

def main(argv):
    sys.stdout.reconfigure(line_buffering=True)
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog='\n'.join(__doc__.split('\n')[27:36]))
    p.add_argument('command', choices=['list', 'handout', 'solution', 'status', 'grade', 'picture', 'check',
                                       'handed-out', 'reference-tree'])
    p.add_argument('number', nargs='?', help='the chapter (picture), or the folder (reference-tree)')
    p.add_argument('--ch', help='the chapter number, e.g. 01')
    p.add_argument('--ex', help='one exercise by name')
    p.add_argument('--build', default='build')
    p.add_argument('--root', default=ROOT)
    p.add_argument('--plant', action='store_true', help='check: refuse a planted exercise no test catches')
    p.add_argument('--keep', action='store_true', help='check: keep the temporary tree')
    rest = argv[argv.index('--') + 1:] if '--' in argv else []
    a = p.parse_args(argv[:argv.index('--')] if '--' in argv else argv)
    root = os.path.abspath(a.root)
    chapter = chapter_dir(root, a.ch) if a.ch else None
    if a.command in ('handout', 'solution') and not chapter:
        raise Refusal('which chapter? make %s CH=NN' % ('exercise' if a.command == 'handout' else 'solution'))
    if a.command == 'list':
        list_exercises(root, chapter)
    elif a.command == 'handout':
        handout(root, chapter, a.ex)
    elif a.command == 'solution':
        solution(root, chapter, a.ex)
    elif a.command == 'status':
        status(root)
    elif a.command == 'grade':
        return grade(root, [chapter] if chapter else chapter_dirs(root), a.build)
    elif a.command == 'picture':
        return picture(root, '%02d' % int(a.number), a.build, rest)
    elif a.command == 'handed-out':
        return 0 if any_handed_out(root) else 1
    elif a.command == 'reference-tree':
        os.makedirs(a.number, exist_ok=True)
        reference_tree(root, os.path.abspath(a.number))
    elif a.command == 'check':
        return check(root, chapter, a.ex, a.plant, a.keep)
    return 0


if __name__ == '__main__':
    try:
        sys.exit(main(sys.argv[1:]))
    except Refusal as e:
        print('exercise: %s' % e, file=sys.stderr)
        sys.exit(2)
