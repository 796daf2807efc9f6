"""`decoy view`: one self-contained HTML page of an evaluate run or a replay.

* decoy_cli/replay/view_trace.py (not here: the replay writes it): a replayed round's paths,
  thinned, and its events;
* page.py: the page, its data and script inline (page.html, page.css, and the script's files
  data.js, draw.js, controls.js, tables.js);
* replay_folder.py: the page's data from a `decoy replay` output folder.
"""
