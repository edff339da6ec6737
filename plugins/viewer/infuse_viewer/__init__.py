"""infuse-anim-viewer: ``infuse view FILE|FOLDER`` shows characters, clips, mappings, audio and targets in a browser.

The page is three.js (bundled from the npm package ``make setup`` installs, never a CDN); it is
served on 127.0.0.1 or written as one offline HTML file.
"""
