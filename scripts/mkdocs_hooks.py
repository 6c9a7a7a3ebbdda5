"""mkdocs hooks for mgrl's site (mkdocs.yml): the reference pages that live beside what
they describe (scenarios/README.md, framework/README.md) join the site, the docs' links to
them are taken as links within it, and a page that no navigation entry reaches is a
warning (an error under --strict)."""
import logging
import os

from mkdocs.structure.files import File

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Pages outside docs/, by their path from the repository's root (and in the site).
OUTSIDE = ["scenarios/README.md", "framework/README.md"]
log = logging.getLogger("mkdocs.hooks.mgrl")


def on_files(files, config):
    for path in OUTSIDE:
        if not os.path.isfile(os.path.join(ROOT, path)):
            log.warning(f"mkdocs_hooks: expected {path} in {ROOT}, found none")
            continue
        files.append(File(path, ROOT, config["site_dir"], config["use_directory_urls"]))
    return files


def on_page_markdown(markdown, page, config, files):
    if page.file.src_path in OUTSIDE:
        # Its links to docs/ pages, as the site places them.
        return markdown.replace("](../docs/", "](../").replace("](../../docs/", "](../../")
    for path in OUTSIDE:  # a docs/ page's ../scenarios/README.md is the site's scenarios/README.md
        folder = path.split("/")[0]
        markdown = markdown.replace(f"](../{folder}/", f"]({folder}/")
    return markdown


def on_nav(nav, config, files):
    reached = {page.file.src_path for page in nav.pages}
    for file in files.documentation_pages():
        if file.src_path not in reached:
            log.warning(f"{file.src_path}: no navigation entry reaches this page (add it to mkdocs.yml's nav and "
                        "docs/index.md)")
    return nav
