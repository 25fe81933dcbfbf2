"""carla.BlueprintLibrary, ActorBlueprint, ActorAttribute, built from the blueprint
declarations the running services publish (lockstep/blueprints), never from a copy."""
import fnmatch
import random
import re

from .geometry import Color

__all__ = ['ActorAttributeType', 'ActorAttribute', 'ActorBlueprint', 'BlueprintLibrary']


class ActorAttributeType:
    Bool = 'bool'
    Int = 'int'
    Float = 'float'
    String = 'string'
    RGBColor = 'rgb'


class ActorAttribute:
    def __init__(self, decl, value=None):
        self._decl = decl
        self.id = decl['id']
        self.type = decl['type']
        self.recommended_values = list(decl['recommended_values'])
        self.is_modifiable = decl['modifiable']
        self._value = decl['default'] if value is None else value

    def as_bool(self):
        return self._value.lower() == 'true'

    def as_int(self):
        return int(self._value)

    def as_float(self):
        return float(self._value)

    def as_str(self):
        return self._value

    def as_color(self):
        r, g, b = (int(v) for v in self._value.split(','))
        return Color(r, g, b)

    def __str__(self):
        return self._value

    def __bool__(self):
        return self.as_bool() if self.type == 'bool' else bool(self._value)

    def __int__(self):
        return self.as_int()

    def __float__(self):
        return self.as_float()

    def __eq__(self, o):
        if isinstance(o, ActorAttribute):
            return self._value == o._value
        if isinstance(o, bool):
            return self.as_bool() == o
        if isinstance(o, (int, float)):
            return self.as_float() == o
        return self._value == str(o)

    def __repr__(self):
        return 'ActorAttribute(id=%s,type=%s,value=%s(const))' % (self.id, self.type, self._value)


def _check_value(decl, value):
    """The service's own rules, checked early so set_attribute raises like CARLA's."""
    t = decl['type']
    name = decl['id']
    try:
        if t == 'bool':
            if value.lower() not in ('true', 'false'):
                raise ValueError
        elif t == 'int':
            v = int(value)
            if not decl['min'] <= v <= decl['max']:
                raise IndexError('attribute %r: %s is outside [%g, %g]' % (name, value, decl['min'], decl['max']))
        elif t == 'float':
            v = float(value)
            if not decl['min'] <= v <= decl['max']:
                raise IndexError('attribute %r: %s is outside [%g, %g]' % (name, value, decl['min'], decl['max']))
        elif t == 'rgb':
            parts = [int(p) for p in value.split(',')]
            if len(parts) != 3 or any(p < 0 or p > 255 for p in parts):
                raise ValueError
    except IndexError as e:
        raise IndexError(str(e))
    except ValueError:
        raise ValueError('attribute %r (%s): %r is not a valid value' % (name, t, value))
    if decl['restricted'] and value not in decl['recommended_values']:
        raise IndexError('attribute %r: %r is not one of %s' % (name, value, decl['recommended_values']))


class ActorBlueprint:
    def __init__(self, decl):
        self._decl = decl
        self.id = decl['id']
        self.tags = [t for t in decl['tags'].split(',') if t] or self.id.split('.')
        self.kind = decl['kind']
        # Attributes whose id starts with '_' are Lockstep's (e.g. ground_sim's '_physics.*'), not CARLA's.
        self._attrs = {a['id']: ActorAttribute(a) for a in decl['attributes'] if not a['id'].startswith('_')}
        self._set = {}
        # CARLA picks one of the recommended values for attributes like color at random.
        for a in decl['attributes']:
            if a['id'] in ('color', 'driver_id') and a['recommended_values']:
                self._attrs[a['id']] = ActorAttribute(a, random.choice(a['recommended_values']))

    def has_tag(self, tag):
        return tag in self.tags

    def match_tags(self, pattern):
        return any(fnmatch.fnmatchcase(t, pattern) for t in self.tags)

    def has_attribute(self, id):
        return id in self._attrs

    def get_attribute(self, id):
        if id not in self._attrs:
            raise IndexError("blueprint '%s' has no attribute '%s' (it has: %s)" % (self.id, id, ', '.join(sorted(self._attrs))))
        return self._attrs[id]

    def set_attribute(self, id, value):
        attr = self.get_attribute(id)
        if not attr.is_modifiable:
            raise IndexError("attribute '%s' of '%s' is not modifiable" % (id, self.id))
        value = str(value)
        if attr.type == 'bool':
            value = value.lower()
        if attr.type == 'int':
            # CARLA reads int attributes with atoi: '64.0' (lidar_to_camera.py's channels) is 64.
            m = re.match(r'\s*([+-]?\d+)', value)
            value = str(int(m.group(1))) if m else value
        _check_value(attr._decl, value)
        self._attrs[id] = ActorAttribute(attr._decl, value)
        self._set[id] = value

    def spawn_attributes(self):
        """What goes on the wire: the values set, plus the randomised recommended ones."""
        out = {}
        for k, a in self._attrs.items():
            if k in self._set or (k in ('color', 'driver_id') and a.recommended_values) or k == 'role_name':
                out[k] = a.as_str()
        if out.get('role_name', None) == '':
            del out['role_name']
        return out

    def __iter__(self):
        return iter(self._attrs.values())

    def __len__(self):
        return len(self._attrs)

    def __repr__(self):
        return 'ActorBlueprint(id=%s,tags=%s)' % (self.id, self.tags)


class BlueprintLibrary:
    def __init__(self, declarations):
        self._decls = list(declarations)

    def _bps(self):
        return [ActorBlueprint(d) for d in self._decls]

    def filter(self, wildcard_pattern):
        out = [d for d in self._decls
               if fnmatch.fnmatchcase(d['id'], wildcard_pattern)
               or any(fnmatch.fnmatchcase(t, wildcard_pattern) for t in d['tags'].split(',') if t)]
        return BlueprintLibrary(out)

    def filter_by_attribute(self, name, value):
        out = []
        for d in self._decls:
            bp = ActorBlueprint(d)
            if bp.has_attribute(name) and bp.get_attribute(name) == value:
                out.append(d)
        return BlueprintLibrary(out)

    def find(self, id):
        for d in self._decls:
            if d['id'] == id:
                return ActorBlueprint(d)
        raise IndexError("blueprint '%s' not found: no running service declares it (%d blueprints declared)"
                         % (id, len(self._decls)))

    def __getitem__(self, i):
        return ActorBlueprint(self._decls[i])

    def __len__(self):
        return len(self._decls)

    def __iter__(self):
        return iter(self._bps())

    def __repr__(self):
        return 'BlueprintLibrary(%s)' % [d['id'] for d in self._decls]
