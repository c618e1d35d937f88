"""crackle.Scene: a validated scene, from a YAML file, YAML text or a dict, with ``--set`` overrides."""
import json
import os

from . import _crackle
from .errors import IoError


def yaml_value(value):
    """The YAML text of a Python value, as ``--set key=TEXT`` takes it: a string as it is, numbers
    in their shortest round-trip form, booleans as true/false, lists and dicts in flow style."""
    if isinstance(value, str):
        return value
    if hasattr(value, "tolist"):  # NumPy scalars and arrays
        value = value.tolist()
    if isinstance(value, tuple):
        value = list(value)
    return json.dumps(value)


class Scene:
    """A scene as ``crackle`` reads it: validated against the parameter table on construction and
    after every :meth:`set`, with the messages (and :class:`crackle.SceneError`) of the command line.

    ``Scene(source)`` takes a path to a YAML file (str or os.PathLike), YAML text (a str with a
    line break) or a dict (the YAML document as Python data). A missing file raises
    :class:`crackle.IoError`. ``name`` stands for the file in messages of a text or dict scene.
    Relative file references of a text or dict scene (``mesh.gmsh``, ``identify`` measurements)
    resolve against ``base`` (default: the current folder).
    """

    def __init__(self, source, name=None, base=None):
        self._overrides = []
        if isinstance(source, dict):
            # JSON is YAML; one key per line keeps the line numbers of messages useful.
            self._path = None
            self._text = json.dumps(source, indent=2) + "\n"
            self.name = name or "<dict>"
        elif isinstance(source, os.PathLike) or (isinstance(source, str) and "\n" not in source):
            path = os.fspath(source)
            if not os.path.isfile(path):
                what = "is a folder" if os.path.isdir(path) else "no such file"
                raise IoError(f"{path}: cannot read the scene file ({what})", exit_code=2)
            self._path = path
            self._text = _crackle.read_scene_file(path)
            self.name = path
        elif isinstance(source, str):
            self._path = None
            self._text = source
            self.name = name or "<text>"
        else:
            raise TypeError(f"Scene: expected a path, YAML text or a dict, got {type(source).__name__}")
        self._base = os.path.abspath(base) if base else os.getcwd()
        self._sections = self._validate(self._overrides)

    @classmethod
    def from_text(cls, text, name="<text>", base=None):
        """A scene from YAML text (also one without a line break)."""
        scene = cls.__new__(cls)
        scene._overrides, scene._path, scene._text, scene.name = [], None, text, name
        scene._base = os.path.abspath(base) if base else os.getcwd()
        scene._sections = scene._validate([])
        return scene

    def _validate(self, overrides):
        return _crackle.validate(self._text, self.name, overrides)

    def set(self, key, value):
        """Overrides one value, as ``--set key=value``: ``scene.set("mesh.box.order", 3)``. The key
        path and the value are checked like the file's own; a bad one raises SceneError and leaves
        the scene as it was. Returns the scene (calls chain)."""
        text = yaml_value(value)
        _crackle.check_override(f"{key}={text}")
        overrides = self._overrides + [(key, text)]
        self._sections = self._validate(overrides)
        self._overrides = overrides
        return self

    def copy(self):
        """An independent copy (its own overrides)."""
        other = Scene.__new__(Scene)
        other.__dict__.update(self.__dict__)
        other._overrides = list(self._overrides)
        return other

    @property
    def path(self):
        """The scene file, or None for a text or dict scene."""
        return self._path

    @property
    def text(self):
        """The YAML text (before the overrides)."""
        return self._text

    @property
    def overrides(self):
        """The overrides as (key path, YAML text) pairs, in order."""
        return list(self._overrides)

    def has(self, section):
        """Whether the scene has a section: transient, spectrum, sweep, modal or crack."""
        return bool(self._sections.get(section, False))

    @staticmethod
    def keys():
        """The parameter table: one dict per key (key, kind, expects, unit, required, default,
        choices, doc), the same table that generates docs/scene-format.md."""
        return _crackle.parameters()

    def mesh(self, for_modal=False):
        """The mesh of the body (crackle.Mesh): the one ``crackle run`` and ``crackle sweep`` use, or
        with ``for_modal`` the one of ``crackle modal`` (graded towards the crack front)."""
        from .results import Mesh, private_scene

        with private_scene(self) as (path, overrides):
            return Mesh(_crackle.mesh(path, overrides, for_modal))

    def __repr__(self):
        extra = "".join(f" --set {key}={value}" for key, value in self._overrides)
        return f"crackle.Scene({self.name!r}{extra})"
