#!/usr/bin/env python3
"""Checks that every private parameter a node reads is documented in its package README.

For each node package (src/scanstop_*/ with C++ sources that read parameters) it collects the
parameter names the code reads -- calls of scanstop_common's reader (ros_params::optional,
ros_params::require<T>), of local wrappers around it (`optional(...)`, `opt(...)` lambdas and
helpers), and of NodeHandle::param/getParam on a private handle -- and the names in the
"## Parameters" section of src/<pkg>/README.md (every `backticked` name in the first column of its
tables). It fails, naming package, parameter and README, for every name the code reads that the
README does not list. Names documented but not read are reported as notes.

Run from the repository root: python3 scripts/check_param_docs.py [--root DIR]. stdlib only.
"""
import argparse
import os
import re
import sys

# A call of the reader or a wrapper: optional(pnh, "name", v), ros_params::require<std::string>(pnh, "name"),
# optional("name", v) (lambda bound to pnh), opt(pnh, "name", v), optional(pnh, prefix + "name", v).
READER_CALL = re.compile(
    r'\b(?:ros_params::)?(?:optional|require\s*<[^>]*>|opt)\s*\(\s*'
    r'(?:[A-Za-z_][\w:.]*(?:\([^()]*\))?\s*,\s*)?'  # the node handle argument, when there is one
    r'(?P<prefix>[A-Za-z_]\w*\s*\+\s*)?'  # a variable prefix: prefix + "name"
    r'"(?P<name>[^"]+)"')
# NodeHandle reads on a private handle: pnh.param("name", ...), private_nh.getParam("name", ...).
HANDLE_CALL = re.compile(
    r'\b(?P<handle>\w+)\s*(?:\.|->)\s*(?:param|getParam|getParamCached|hasParam)\s*(?:<[^>]*>)?\s*\(\s*"(?P<name>[^"]+)"')
PRIVATE_HANDLES = {'pnh', 'nh_private', 'private_nh', 'pnh_', 'nh_private_', 'private_nh_'}
BACKTICK = re.compile(r'`([^`]+)`')
SKIP_PACKAGES = {'scanstop_common', 'scanstop_msgs'}  # no node: the reader itself, messages


def strip_comments(text):
    text = re.sub(r'/\*.*?\*/', lambda m: '\n' * m.group(0).count('\n'), text, flags=re.S)
    return re.sub(r'//[^\n]*', '', text)


def code_parameters(pkg_dir):
    """{name: [file:line, ...]}; a name read with a variable prefix is stored as '*' + name."""
    found = {}
    for sub in ('src', 'include'):
        for dirpath, _, files in os.walk(os.path.join(pkg_dir, sub)):
            for f in sorted(files):
                if not f.endswith(('.cpp', '.cc', '.h', '.hpp')):
                    continue
                path = os.path.join(dirpath, f)
                text = strip_comments(open(path, encoding='utf-8', errors='replace').read())
                hits = [(m, m.group('name'), bool(m.group('prefix'))) for m in READER_CALL.finditer(text)]
                hits += [(m, m.group('name'), False) for m in HANDLE_CALL.finditer(text)
                         if m.group('handle') in PRIVATE_HANDLES]
                for m, name, prefixed in hits:
                    if name.startswith('/'):
                        continue  # a global parameter (e.g. /use_sim_time), not the node's
                    name = name.lstrip('~')
                    key = '*' + name if prefixed else name
                    line = text.count('\n', 0, m.start()) + 1
                    found.setdefault(key, []).append('%s:%d' % (os.path.relpath(path), line))
    return found


def readme_parameters(readme):
    """Names in the README's '## Parameters' section tables (first column), or None without one."""
    if not os.path.isfile(readme):
        return None
    names, in_section, seen_section, fence = set(), False, False, False
    for line in open(readme, encoding='utf-8'):
        if line.startswith('```'):
            fence = not fence
        if fence:
            continue
        if re.match(r'^##\s', line):
            in_section = re.match(r'^##\s+Parameters\b', line) is not None
            seen_section = seen_section or in_section
            continue
        if in_section and line.startswith('|') and not re.match(r'^\|\s*-', line):
            first = line.split('|')[1]
            names.update(n.strip().lstrip('~') for n in BACKTICK.findall(first))
    return names if seen_section else None


def documented(name, names):
    """A code name matches a README name; README placeholders <x> match one name component; a
    code name read with a variable prefix ('*' + name) matches any README name ending in /name."""
    for doc in names:
        pattern = '^' + re.sub(r'\\<[^>]*\\>', '[^/]+', re.escape(doc)) + '$'
        if name.startswith('*'):
            if doc == name[1:] or doc.endswith('/' + name[1:]):
                return True
        elif re.match(pattern, name):
            return True
    return False


SELF_TEST_CODE = r'''
  c.port = ros_params::require<std::string>(pnh, "port");
  ros_params::optional(pnh, "scanner/height", sc.height_m);
  ros_params::optional(pnh, pp + "sensor/p_hit", sn.p_hit);
  optional("relax", config.relax);
  opt(pnh, "motion/max_forward", m.max_forward_m);
  optional(ros::NodeHandle(nh, ns), "frame_id", n.frame_id);
  pnh.param("rate", rate_, 10.0);
  nh.param("/use_sim_time", clock_, false);  // global: not the node's
  // ros_params::optional(pnh, "commented_out", x);
'''
SELF_TEST_README = """# scanstop_x

## Parameters

| name | type | default | unit | meaning |
|---|---|---|---|---|
| `port` | string | required | | |
| `scanner/height`, `frame_id` | double, string | 0.45, map | m | |
| `profiles/<name>/sensor/p_hit` | double | 0.97 | | |
| `relax` | bool | false | | |
| `motion/max_forward` | double | 5 | m | |
| `rate` | double | 10 | Hz | |

## Services
| `not_a_parameter` | | |
"""


def self_test():
    """The checker finds every call form above and fails on a removed row."""
    import shutil
    import subprocess
    import tempfile
    tmp = tempfile.mkdtemp()
    try:
        pkg = os.path.join(tmp, 'src', 'scanstop_x')
        os.makedirs(os.path.join(pkg, 'src'))
        open(os.path.join(pkg, 'src', 'node.cpp'), 'w').write(SELF_TEST_CODE)
        found = set(code_parameters(pkg))
        expected = {'port', 'scanner/height', '*sensor/p_hit', 'relax', 'motion/max_forward', 'frame_id', 'rate'}
        ok = found == expected
        print('self-test: names found %s' % ('OK' if ok else 'WRONG: %s, expected %s' % (sorted(found), sorted(expected))))
        readme = os.path.join(pkg, 'README.md')
        runs = []
        for removed in (None, '| `relax`', '| `profiles/', '| `scanner/height`'):
            text = ''.join(l for l in SELF_TEST_README.splitlines(True) if not (removed and l.startswith(removed)))
            open(readme, 'w').write(text)
            rc = subprocess.run([sys.executable, os.path.abspath(__file__), '--root', tmp],
                                stdout=subprocess.DEVNULL).returncode
            runs.append(rc == (0 if removed is None else 1))
            print('self-test: README %s -> exit %d (%s)' % ('complete' if removed is None else 'without ' + removed.strip('| '),
                                                            rc, 'OK' if runs[-1] else 'WRONG'))
        return 0 if ok and all(runs) else 1
    finally:
        shutil.rmtree(tmp)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--root', default='.', help='repository root (default: .)')
    ap.add_argument('--self-test', action='store_true', help='check the checker on a generated package')
    args = ap.parse_args()
    if args.self_test:
        return self_test()
    src = os.path.join(args.root, 'src')
    failures, checked = [], 0
    for pkg in sorted(os.listdir(src)):
        pkg_dir = os.path.join(src, pkg)
        if not (pkg.startswith('scanstop_') and os.path.isdir(pkg_dir)) or pkg in SKIP_PACKAGES:
            continue
        code = code_parameters(pkg_dir)
        if not code:
            continue
        readme = os.path.relpath(os.path.join(pkg_dir, 'README.md'))
        names = readme_parameters(readme)
        if names is None:
            failures.append('%s: %s has no "## Parameters" section (the code reads %d parameters)'
                            % (pkg, readme, len(code)))
            continue
        missing = [n for n in sorted(code) if not documented(n, names)]
        for n in missing:
            failures.append('%s: parameter %s (read at %s) is not in the Parameters table of %s'
                            % (pkg, ('<prefix>' + n[1:]) if n.startswith('*') else n, code[n][0], readme))
        unread = sorted(d for d in names if not any(documented(c, {d}) for c in code))
        for d in unread:
            print('note: %s: %s lists %s, which the code does not read' % (pkg, readme, d))
        checked += 1
        print('%s: %d parameters read by the code, %d missing from %s' % (pkg, len(code), len(missing), readme))
    for f in failures:
        print('FAIL: ' + f)
    print('check_param_docs: %d packages, %s' % (checked, 'OK' if not failures else '%d failures' % len(failures)))
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
