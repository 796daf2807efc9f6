"""`decoy view`: one self-contained HTML page of an evaluate run or a replay.

* trace.py: a replayed round's paths (thinned) and events, kept with its results;
* page.py: the page, its data and script inline (page.html, page.js, page.css);
* replay_folder.py: the page's data from a `decoy replay` output folder.
"""
