"""deploy/k8s and deploy/compose.yaml, checked offline (no cluster, no network): every
Kubernetes object against the Kubernetes API schema as Debian's python3-kubernetes models
carry it (generated from the API's OpenAPI definition: field names, types, required
fields; an unknown or misspelt field fails), plus what the schema cannot see: selectors
that match their pods, Services that reach a port, volumes that exist, one pod per service
of the launch config, images that deploy/containers builds, and QoS files that are what
deploy/containers/make_qos.py makes from deploy/qos/fastdds.xml today."""
import os
import re
import subprocess
import sys

import pytest
import yaml

kubernetes = pytest.importorskip('kubernetes', reason='python3-kubernetes (Debian) is not installed')
from kubernetes import client  # noqa: E402

SOURCE = os.path.abspath(os.environ.get('LOCKSTEP_SOURCE', os.path.join(os.path.dirname(__file__), '..', '..')))
DEPLOY = os.path.join(SOURCE, 'deploy')
K8S = os.path.join(DEPLOY, 'k8s')
CONTAINERS = os.path.join(DEPLOY, 'containers')
DNS1123 = re.compile(r'[a-z0-9]([-a-z0-9]*[a-z0-9])?')


def check_schema(data, type_name, path, errors):
    """Walks `data` along the model types of python3-kubernetes; appends what is wrong."""
    if data is None:
        return
    m = re.fullmatch(r'list\[(.+)\]', type_name)
    if m:
        if not isinstance(data, list):
            errors.append('%s: a list expected, got %r' % (path, data))
            return
        for i, item in enumerate(data):
            check_schema(item, m.group(1), '%s[%d]' % (path, i), errors)
        return
    m = re.fullmatch(r'dict\(str, (.+)\)', type_name)
    if m:
        if not isinstance(data, dict):
            errors.append('%s: a map expected, got %r' % (path, data))
            return
        for k, v in data.items():
            if not isinstance(k, str):
                errors.append('%s: key %r is not a string' % (path, k))
            check_schema(v, m.group(1), '%s.%s' % (path, k), errors)
        return
    scalars = {'str': (str,), 'int': (int,), 'float': (int, float), 'bool': (bool,), 'object': (object,),
               'datetime': (str,), 'date': (str,)}
    if type_name in scalars:
        ok = isinstance(data, scalars[type_name]) and not (type_name in ('int', 'float') and isinstance(data, bool))
        if not ok:
            errors.append('%s: %s expected, got %r' % (path, type_name, data))
        return
    model = getattr(client, type_name, None)
    if model is None:
        errors.append('%s: unknown schema type %s' % (path, type_name))
        return
    if not isinstance(data, dict):
        errors.append('%s: an object (%s) expected, got %r' % (path, type_name, data))
        return
    by_json = {j: p for p, j in model.attribute_map.items()}
    for key, value in data.items():
        if key not in by_json:
            errors.append('%s: %s has no field %r' % (path, type_name, key))
            continue
        check_schema(value, model.openapi_types[by_json[key]], '%s.%s' % (path, key), errors)


def validate(obj, where):
    """Schema errors of one Kubernetes object (a dict from YAML)."""
    errors = []
    api, kind = obj.get('apiVersion'), obj.get('kind')
    if not api or not kind:
        return ['%s: no apiVersion/kind' % where]
    type_name = api.split('/')[-1].capitalize() + kind
    if getattr(client, type_name, None) is None:
        return ['%s: %s %s is not a Kubernetes type' % (where, api, kind)]
    check_schema(obj, type_name, '%s %s' % (where, kind), errors)
    if not errors:
        # Required fields and enumerations: the models' own checks while deserializing.
        try:
            client.ApiClient()._ApiClient__deserialize(obj, type_name)
        except (ValueError, TypeError) as e:
            errors.append('%s %s: %s' % (where, kind, e))
    name = (obj.get('metadata') or {}).get('name', '')
    if not DNS1123.fullmatch(name or '') or len(name) > 63:
        errors.append('%s %s: name %r is not a DNS-1123 label' % (where, kind, name))
    return errors


def load(path):
    with open(path) as f:
        return [d for d in yaml.safe_load_all(f) if d is not None]


def kustomization():
    return load(os.path.join(K8S, 'kustomization.yaml'))[0]


def objects():
    """Every object that `kubectl apply -k deploy/k8s` creates, the generated ConfigMap
    included (as kustomize's configMapGenerator makes it, without the name suffix)."""
    k = kustomization()
    out = []
    for r in k['resources']:
        out += [(r, o) for o in load(os.path.join(K8S, r))]
    for g in k.get('configMapGenerator', []):
        data = {os.path.basename(f): open(os.path.join(K8S, f)).read() for f in g['files']}
        out.append(('kustomization.yaml', {'apiVersion': 'v1', 'kind': 'ConfigMap', 'metadata': {'name': g['name']},
                                           'data': data}))
    return out


def test_every_object_matches_the_kubernetes_schema():
    objs = objects()
    assert len(objs) >= 10
    errors = [e for where, o in objs for e in validate(o, where)]
    assert not errors, '\n'.join(errors)


def test_the_validator_refuses_what_kubernetes_refuses():
    """The check is not vacuous: a misspelt field, a wrong type, a missing required field."""
    dep = next(o for _, o in objects() if o['kind'] == 'Deployment')
    import copy
    bad = copy.deepcopy(dep)
    bad['spec']['template']['spec']['contaners'] = bad['spec']['template']['spec'].pop('containers')
    assert any("no field 'contaners'" in e for e in validate(bad, 'x'))
    bad = copy.deepcopy(dep)
    bad['spec']['replicas'] = 'one'
    assert any('int expected' in e for e in validate(bad, 'x'))
    bad = copy.deepcopy(dep)
    del bad['spec']['selector']
    assert any('selector' in e for e in validate(bad, 'x'))


def pods():
    """(object, pod spec, pod labels) of every workload."""
    for where, o in objects():
        if o['kind'] in ('Deployment', 'Job'):
            t = o['spec']['template']
            yield o, t['spec'], (t.get('metadata') or {}).get('labels', {})


def test_selectors_services_volumes_and_images_fit_together():
    objs = [o for _, o in objects()]
    names = {(o['kind'], o['metadata']['name']) for o in objs}
    for o, spec, labels in pods():
        if o['kind'] == 'Deployment':
            sel = o['spec']['selector']['matchLabels']
            assert sel.items() <= labels.items(), '%s: selector %s does not match its pods %s' % (
                o['metadata']['name'], sel, labels)
        volumes = {v['name']: v for v in spec.get('volumes', [])}
        for c in spec['containers']:
            for m in c.get('volumeMounts', []):
                assert m['name'] in volumes, '%s: mount of an undeclared volume %s' % (o['metadata']['name'], m['name'])
            image = re.fullmatch(r'localhost/lockstep/([a-z_]+):latest', c['image'])
            assert image and os.path.exists(os.path.join(CONTAINERS, 'Containerfile.' + image.group(1))), c['image']
        for v in volumes.values():
            if 'configMap' in v:
                assert ('ConfigMap', v['configMap']['name']) in names, v
            if 'persistentVolumeClaim' in v:
                assert ('PersistentVolumeClaim', v['persistentVolumeClaim']['claimName']) in names, v
    for s in (o for o in objs if o['kind'] == 'Service'):
        matched = [(o, spec) for o, spec, labels in pods() if s['spec']['selector'].items() <= labels.items()]
        assert matched, 'Service %s selects no pod' % s['metadata']['name']
        ports = {p['containerPort'] for _, spec in matched for c in spec['containers'] for p in c.get('ports', [])}
        for p in s['spec']['ports']:
            assert p.get('targetPort', p['port']) in ports, 'Service %s: port %s reaches no container' % (
                s['metadata']['name'], p)


def test_one_pod_per_service_of_the_launch_config_and_the_render_pod_fits_gpu_nodes():
    config = yaml.safe_load(open(os.path.join(K8S, 'sim.yaml')))
    wanted = {s['name'] for s in config['services']}
    started = {}
    for o, spec, _ in pods():
        args = spec['containers'][0].get('args', [])
        if '--name' in args:
            started[args[args.index('--name') + 1]] = (o, spec)
            assert o['spec']['replicas'] == 1 and o['spec']['strategy']['type'] == 'Recreate', o['metadata']['name']
    assert set(started) == wanted, 'pods %s, services of sim.yaml %s' % (sorted(started), sorted(wanted))
    coordinators = [o for o, spec, _ in pods() if 'coordinator' in spec['containers'][0]['image']]
    assert len(coordinators) == 1
    _, render = started['render']
    assert any(t.get('key') == 'nvidia.com/gpu' for t in render.get('tolerations', [])), render
    assert 'nodeAffinity' in render.get('affinity', {}), render
    outputs = [n for n, (o, spec) in started.items() if any(v.get('persistentVolumeClaim') for v in spec.get('volumes', []))]
    assert {'recorder', 'sensors', 'render'} <= set(outputs), outputs
    assert any(o['kind'] == 'Job' for o, _, _ in pods())
    # No namespace anywhere: one simulation per namespace is `kubectl apply -n NS -k deploy/k8s`.
    assert all('namespace' not in o['metadata'] for _, o in objects())


def make_qos(*args):
    return subprocess.run([sys.executable, os.path.join(CONTAINERS, 'make_qos.py')] + list(args), check=True,
                          stdout=subprocess.PIPE, text=True).stdout


def test_the_qos_files_are_what_make_qos_makes_from_the_current_profiles():
    assert open(os.path.join(K8S, 'fastdds.xml')).read() == make_qos('--discovery-server', 'lockstep-discovery:11811'), \
        'regenerate: deploy/containers/make_qos.py --discovery-server lockstep-discovery:11811 -o deploy/k8s/fastdds.xml'
    assert open(os.path.join(DEPLOY, 'compose', 'fastdds.xml')).read() == make_qos('--discovery-server', 'discovery:11811'), \
        'regenerate: deploy/containers/make_qos.py --discovery-server discovery:11811 -o deploy/compose/fastdds.xml'
    assert open(os.path.join(DEPLOY, 'security', 'fastdds.xml')).read() == make_qos('--security'), \
        'regenerate: deploy/containers/make_qos.py --security -o deploy/security/fastdds.xml'


def test_make_qos_rejects_bad_input():
    for args in (['--peers', ''], ['--peers', 'a b'], ['--discovery-server', 'nohostport']):
        p = subprocess.run([sys.executable, os.path.join(CONTAINERS, 'make_qos.py')] + args, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, text=True)
        assert p.returncode != 0 and 'make_qos.py' in p.stderr, (args, p.stderr)


def test_compose_runs_every_service_of_its_config_and_a_client():
    compose = load(os.path.join(DEPLOY, 'compose.yaml'))[0]
    config = yaml.safe_load(open(os.path.join(DEPLOY, 'compose', 'sim.yaml')))
    services = compose['services']
    started = {}
    for name, s in services.items():
        image = re.fullmatch(r'localhost/lockstep/([a-z_]+):latest', s['image'])
        assert image and os.path.exists(os.path.join(CONTAINERS, 'Containerfile.' + image.group(1))), s['image']
        cmd = s.get('command', [])
        if '--name' in cmd:
            started[cmd[cmd.index('--name') + 1]] = s
        assert 'network_mode' not in s and 'ipc' not in s, '%s shares a namespace' % name
        assert not any('/dev/shm' in str(v) for v in s.get('volumes', [])), '%s shares /dev/shm' % name
    assert set(started) == {s['name'] for s in config['services']}
    assert 'coordinator' in services and 'discovery' in services
    assert 'read_states.py' in ' '.join(services['client']['command'])
