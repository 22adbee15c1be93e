"""The one DOM helper the model's edits share (xml.dom.minidom, as xacro hands documents over)."""


def child_elements(element, tag):
    """The direct children of `element` named `tag`, in document order (not the deeper ones)."""
    return [n for n in element.childNodes if n.nodeType == n.ELEMENT_NODE and n.tagName == tag]
