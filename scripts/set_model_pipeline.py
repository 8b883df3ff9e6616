#!/usr/bin/env python3
"""Writes a copy of an agex model with some of its pipeline settings changed.

  scripts/set_model_pipeline.py MODEL.yml COPY.yml KEY=JSON [KEY=JSON ...]
  e.g. scripts/set_model_pipeline.py agex_bonn.yml box.yml isolate_people=false use_crop_box=true

To score one trained model under other pipeline settings (agex_eval detect runs the pipeline a
model stores; doc/pipeline.md lists the keys and their ranges, which the detector checks when it
loads the copy). The classifier is untouched; a fused model's forest and window model are looked
up beside the copy, so write the copy next to them or copy them beside it. Refuses to write over
an existing file.
"""
import json
import os
import re
import sys


def main(argv):
    if len(argv) < 4:
        sys.exit(__doc__)
    src, dst, pairs = argv[1], argv[2], argv[3:]
    if os.path.exists(dst):
        sys.exit(f"set_model_pipeline: {dst} exists; not overwritten")
    with open(src) as f:
        lines = f.read().split('\n')
    try:
        start = lines.index('metadata:') + 1
    except ValueError:
        sys.exit(f"set_model_pipeline: {src}: no metadata (not an agex model?)")
    end, chunks = start, []
    while end < len(lines) and lines[end].startswith('   - "|'):
        m = re.fullmatch(r'   - "\|(.*)\|"', lines[end])
        if not m:
            sys.exit(f"set_model_pipeline: {src}: line {end + 1}: damaged metadata chunk")
        chunks.append(m.group(1).replace('\\"', '"').replace('\\\\', '\\'))
        end += 1
    meta = json.loads(''.join(chunks))
    if 'pipeline' not in meta:
        sys.exit(f"set_model_pipeline: {src}: no pipeline settings")
    for pair in pairs:
        key, _, value = pair.partition('=')
        # Settings added since older models were written: absent there, allowed here.
        if key not in meta['pipeline'] and key not in ('depth_step_growth', 'hidden_people', 'working_spacing', 'min_separation'):
            sys.exit(f"set_model_pipeline: unknown pipeline setting '{key}' (doc/pipeline.md)")
        meta['pipeline'][key] = json.loads(value)
    text = json.dumps(meta, separators=(',', ':'), sort_keys=True, ensure_ascii=True)
    # The model format's chunks: at most 1000 characters, fenced by '|', YAML-escaped.
    lines[start:end] = ['   - "|' + text[i:i + 1000].replace('\\', '\\\\').replace('"', '\\"') + '|"'
                        for i in range(0, len(text), 1000)]
    tmp = dst + '.tmp'
    with open(tmp, 'x') as f:
        f.write('\n'.join(lines))
    os.rename(tmp, dst)


if __name__ == '__main__':
    main(sys.argv)
